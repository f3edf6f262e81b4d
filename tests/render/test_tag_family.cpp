// The one tag-family table (render/tag_family.hpp): lookup by name, the error for an unknown
// name, and every family in it rendered and decoded by libapriltag with corner k at the projected
// corner k.
#include <apriltag/apriltag.h>
#include <gtest/gtest.h>

#include "fixtures.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::render {
namespace {

TEST(RenderTagFamily, LookupByName) {
  ASSERT_EQ(tag_families().size(), 8u);
  for (const auto& f : tag_families()) {
    EXPECT_EQ(find_tag_family(f.name), &f);
    EXPECT_NE(tag_family_names().find(f.name), std::string::npos);
  }
  EXPECT_EQ(find_tag_family("tag99h1"), nullptr);
  try {
    create_tag_family("tag99h1");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "unknown tag family 'tag99h1' (supported: " + tag_family_names() + ")");
  }
}

TEST(RenderTagFamily, EveryFamilyIsRenderedAndDecodedAtItsProjectedCorners) {
  for (const auto& f : tag_families()) {
    SCOPED_TRACE(f.name);
    auto scene = testing::single_tag_scene(
        testing::facing_pose(Vec3(0.05, -0.03, 1.2), Vec3(0.25, -0.2, 0.6)), /*spp=*/4);
    scene.target().tag.family = f.name;
    scene.target().tag.id = 3;
    Renderer r(scene);
    const cv::Mat img = r.render(0, 0);
    const FrameTruth gt = r.truth(0, 0);
    const TagFamilyPtr fam = create_tag_family(f.name);
    apriltag_detector_t* td = apriltag_detector_create();
    // One corrected bit: the default two make libapriltag build a quick-decode table of tens of
    // millions of entries for the 48,714 codes of tagStandard52h13 (a minute of allocation). A
    // clean rendering must decode exactly, which the hamming assertion below checks.
    apriltag_detector_add_family_bits(td, fam.get(), 1);
    td->quad_decimate = 1.0;
    td->nthreads = 1;
    image_u8_t im{img.cols, img.rows, int(img.step), const_cast<uint8_t*>(img.ptr<uint8_t>())};
    zarray_t* dets = apriltag_detector_detect(td, &im);
    ASSERT_EQ(zarray_size(dets), 1);
    apriltag_detection_t* d;
    zarray_get(dets, 0, &d);
    EXPECT_EQ(d->id, 3);
    EXPECT_EQ(d->hamming, 0);
    for (int k = 0; k < 4; ++k) {
      // libapriltag reports pixel centres at +0.5 (test_corner_order.cpp).
      const Vec2 det = Vec2(d->p[k][0], d->p[k][1]) - Vec2(0.5, 0.5);
      EXPECT_LT((det - *gt.corners[size_t(k)]).norm(), 0.5) << "corner " << k;
    }
    apriltag_detections_destroy(dets);
    apriltag_detector_destroy(td);
  }
}

}  // namespace
}  // namespace netvmo::render
