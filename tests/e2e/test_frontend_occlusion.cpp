// Partly occluded tags on rendered images: the front end never accepts a quad with a corner
// more than 1 px from the renderer's projected corner (the border / quiet-zone check rejects
// quads with a side on an occluder's outline or on the image border), and a fully visible tag
// is still detected. Each test also runs the front end without the check on the same images
// and requires wrong corners there, so the scenario does provoke what the check is for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"
#include "netvmo/render/renderer.hpp"
#include "truth_compare.hpp"

namespace fs = std::filesystem;
using namespace netvmo;
using netvmo::testing::max_corner_error;
using netvmo::testing::narrowest_side;

namespace {
const fs::path kSource = NETVMO_SOURCE_DIR;

struct Tally {
  int images = 0;
  int accepted = 0, off_by_more_than_1px = 0;     ///< with the check (the default front end)
  int accepted_unchecked = 0, off_unchecked = 0;  ///< the same images without the check
  int border_mismatch = 0;
  int fully_visible = 0, fully_visible_detected = 0;  ///< narrowest side >= 24 px
};

/// Runs the front end with and without the border check on one rendered image.
void observe(const cv::Mat& img, const io::Calibration& calib, const render::FrameTruth& t,
             frontend::FrontEnd& checked, frontend::FrontEnd& unchecked, Tally& s) {
  ++s.images;
  const auto with = checked.observe(img, calib);
  const auto without = unchecked.observe(img, calib);
  const std::string where = "frame " + std::to_string(t.frame) + " camera " +
                            std::to_string(t.camera_id) + " (visible " +
                            std::to_string(t.visible_fraction) + ")";
  if (without.delta) {
    ++s.accepted_unchecked;
    s.off_unchecked += max_corner_error(without.corners_px, t) > 1.0;
  }
  if (with.delta) {
    ++s.accepted;
    const double e = max_corner_error(with.corners_px, t);
    s.off_by_more_than_1px += e > 1.0;
    EXPECT_LE(e, 1.0) << where;
  }
  if (with.status == frontend::TargetStatus::border_mismatch) {
    ++s.border_mismatch;
    EXPECT_FALSE(with.reason.empty()) << where;
  }
  if (t.in_fov && t.visible_fraction >= 0.999 && narrowest_side(t) >= 24.0) {
    ++s.fully_visible;
    s.fully_visible_detected += with.delta;
    EXPECT_TRUE(with.delta) << where << ": " << frontend::to_string(with.status) << " "
                            << with.reason;
  }
}

void print(const char* what, const Tally& s) {
  std::printf(
      "%s: %d images; without the check %d accepted, %d with a corner > 1 px off; with "
      "it %d accepted, %d off, %d border_mismatch; fully visible (side >= 24 px) %d of "
      "%d detected\n",
      what, s.images, s.accepted_unchecked, s.off_unchecked, s.accepted, s.off_by_more_than_1px,
      s.border_mismatch, s.fully_visible_detected, s.fully_visible);
}

frontend::DetectorSettings settings(int target_id, bool border_check) {
  frontend::DetectorSettings d;
  d.target_id = target_id;
  d.border_check = border_check;
  return d;
}
}  // namespace

TEST(FrontEndOcclusion, OccluderSweepNoCornerOffAndEveryVisibleTagKept) {
  // occluder_sweep.yaml: a bright and then a dark board slide over a static tag in ~0.6 px
  // steps. Every frame of every camera is rendered, in a window around the tag only: the same
  // rays as the full 640x480 frame (the principal point moves with the window), ~10x fewer
  // pixels. The window holds the tag, its quiet zone and half a tag of margin on every side.
  auto scene = io::load_render_scenario(kSource / "datasets/occluder_sweep.yaml");
  {
    render::Renderer full(scene);
    for (int i = 0; i < full.camera_count(); ++i) {
      const auto t = full.truth(i, 0);
      ASSERT_TRUE(t.in_fov);
      double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
      for (const auto& c : t.corners) {
        x0 = std::min(x0, c->x()), x1 = std::max(x1, c->x());
        y0 = std::min(y0, c->y()), y1 = std::max(y1, c->y());
      }
      const double grow = std::max(x1 - x0, y1 - y0);
      auto& k = scene.cameras[static_cast<size_t>(i)].intrinsics;
      const int left = std::max(0, static_cast<int>(x0 - grow)),
                top = std::max(0, static_cast<int>(y0 - grow));
      k.width = std::min(k.width, static_cast<int>(x1 + grow)) - left;
      k.height = std::min(k.height, static_cast<int>(y1 + grow)) - top;
      k.cx -= left;
      k.cy -= top;
    }
  }
  render::Renderer r(scene);
  frontend::FrontEnd checked(settings(scene.target().tag.id, true)),
      unchecked(settings(scene.target().tag.id, false));
  Tally s;
  for (int k = 0; k < r.frame_count(); ++k)
    for (int i = 0; i < r.camera_count(); ++i)
      observe(r.render(i, k), io::scene_calibration(scene.cameras[static_cast<size_t>(i)]),
              r.truth(i, k), checked, unchecked, s);
  print("occluder_sweep", s);
  EXPECT_EQ(s.off_by_more_than_1px, 0);
  EXPECT_EQ(s.fully_visible_detected, s.fully_visible);
  EXPECT_GE(s.fully_visible, 60);
  EXPECT_GE(s.off_unchecked, 10);  // the sweep does provoke quads on the boards' outlines
}

TEST(FrontEndOcclusion, MovingTargetNoCornerOffOnPartlyVisibleTags) {
  // moving_target.yaml, every frame where the tag is partly visible (partly occluded, or partly
  // outside the image); the fully visible frames are DetectionAgreesWithGeometricVisibility's.
  // Shadows off as there, so that visibility is geometry only.
  auto scene = io::load_render_scenario(kSource / "datasets/moving_target.yaml");
  for (auto& light : scene.lights) light.shadows = false;
  render::Renderer r(scene);
  frontend::FrontEnd checked(settings(scene.target().tag.id, true)),
      unchecked(settings(scene.target().tag.id, false));
  Tally s;
  for (int k = 0; k < r.frame_count(); ++k)
    for (int i = 0; i < r.camera_count(); ++i) {
      const auto t = r.truth(i, k);
      if (t.visible_fraction == 0.0 || (t.in_fov && t.visible_fraction >= 0.999)) continue;
      observe(r.render(i, k), io::scene_calibration(scene.cameras[static_cast<size_t>(i)]), t,
              checked, unchecked, s);
    }
  print("moving_target, partly visible", s);
  EXPECT_EQ(s.off_by_more_than_1px, 0);
  EXPECT_GE(s.images, 50);
  EXPECT_GE(s.off_unchecked, 1);  // the image border cutting the quiet zone (camera 2)
}
