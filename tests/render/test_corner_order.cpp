// Proves the tag corner convention: libapriltag's detection corner k is the projection of
// c0 = (-s/2,-s/2,0), c1 = (s/2,-s/2,0), c2 = (s/2,s/2,0), c3 = (-s/2,s/2,0) of the object frame
// (x right, y up the printed tag, z out of the face), for tags rendered at several in-plane
// rotations, and measures libapriltag's pixel-centre offset.
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <gtest/gtest.h>

#include <cstdio>

#include "fixtures.hpp"

namespace netvmo::render {
namespace {

struct Detection {
  int id;
  Vec2 corner[4];
};

std::vector<Detection> detect(const cv::Mat& img) {
  apriltag_family_t* tf = tag36h11_create();
  apriltag_detector_t* td = apriltag_detector_create();
  apriltag_detector_add_family(td, tf);
  td->quad_decimate = 1.0;
  td->nthreads = 1;
  td->refine_edges = 1;
  image_u8_t im{img.cols, img.rows, int(img.step), const_cast<uint8_t*>(img.ptr<uint8_t>())};
  zarray_t* dets = apriltag_detector_detect(td, &im);
  std::vector<Detection> out;
  for (int i = 0; i < zarray_size(dets); ++i) {
    apriltag_detection_t* d;
    zarray_get(dets, i, &d);
    Detection det;
    det.id = d->id;
    for (int k = 0; k < 4; ++k) det.corner[k] = Vec2(d->p[k][0], d->p[k][1]);
    out.push_back(det);
  }
  apriltag_detections_destroy(dets);
  apriltag_detector_destroy(td);
  tag36h11_destroy(tf);
  return out;
}

TEST(CornerOrder, DetectionCornerKIsProjectedCornerK) {
  Vec2 offset_sum = Vec2::Zero();
  int n = 0;
  for (int id : {0, 7}) {
    for (double angle : {0.0, M_PI / 2, M_PI, -M_PI / 2, 0.6}) {
      SCOPED_TRACE("id " + std::to_string(id) + " in-plane angle " + std::to_string(angle));
      auto scene = testing::single_tag_scene(
          testing::facing_pose(Vec3(0.05, -0.03, 1.2), Vec3(0.25, -0.2, angle)));
      scene.target().tag.id = id;
      scene.imaging.noise = true;  // the detector must work on realistic images
      Renderer r(scene);
      const cv::Mat img = r.render(0, 0);
      const FrameTruth gt = r.truth(0, 0);
      const auto dets = detect(img);
      ASSERT_EQ(dets.size(), 1u);
      EXPECT_EQ(dets[0].id, id);
      for (int k = 0; k < 4; ++k) {
        ASSERT_TRUE(gt.corners[size_t(k)].has_value());
        // libapriltag reports pixel centres at +0.5 (see offset below): subtract it.
        const Vec2 det = dets[0].corner[k] - Vec2(0.5, 0.5);
        const Vec2 d = det - *gt.corners[size_t(k)];
        EXPECT_LT(d.norm(), 1.0) << "corner " << k << " detected " << det.transpose() << " truth "
                                 << gt.corners[size_t(k)]->transpose();
        offset_sum += dets[0].corner[k] - *gt.corners[size_t(k)];
        ++n;
      }
    }
  }
  const Vec2 mean = offset_sum / n;
  std::printf(
      "mean (libapriltag corner - projected OpenCV corner) = (%.3f, %.3f) px over %d corners\n",
      mean.x(), mean.y(), n);
  // The documented +0.5 px offset of libapriltag's corners, measured.
  EXPECT_NEAR(mean.x(), 0.5, 0.2);
  EXPECT_NEAR(mean.y(), 0.5, 0.2);
}

// With strong lens distortion the rendered rays must follow the inverse of the OpenCV model that
// the ground truth uses forward: an off-centre tag, displaced ~4 px by distortion, is detected at
// the distorted projection (an undistorted or doubly distorted ray table misses by 4-8 px).
TEST(CornerOrder, DistortedCameraDetectionMatchesDistortedProjection) {
  auto scene =
      testing::single_tag_scene(testing::facing_pose(Vec3(0.3, 0.2, 1.0), Vec3(0.1, -0.2, 0.3)));
  scene.cameras[0].intrinsics.dist = {-0.25, 0.08, 0.002, -0.001, 0.0};
  scene.imaging.noise = true;
  Renderer r(scene);
  const FrameTruth gt = r.truth(0, 0);
  const auto dets = detect(r.render(0, 0));
  ASSERT_EQ(dets.size(), 1u);
  const Pose g_io = gt.g_io;
  double shift = 0;  // how far distortion moves the corners
  for (int k = 0; k < 4; ++k) {
    const Vec3 c = g_io * Vec3(k == 1 || k == 2 ? 0.1 : -0.1, k >= 2 ? 0.1 : -0.1, 0);
    const Vec2 pinhole(600 * c.x() / c.z() + 319.5, 600 * c.y() / c.z() + 239.5);
    shift = std::max(shift, (pinhole - *gt.corners[size_t(k)]).norm());
    const Vec2 det = dets[0].corner[k] - Vec2(0.5, 0.5);
    EXPECT_LT((det - *gt.corners[size_t(k)]).norm(), 1.0) << "corner " << k;
  }
  EXPECT_GT(shift, 3.0);  // the test is only meaningful if distortion moves corners visibly
}

}  // namespace
}  // namespace netvmo::render
