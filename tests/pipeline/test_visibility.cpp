// Detection agrees with geometric visibility on a synthesized moving-target sequence: fully
// visible and large enough -> detected; out of view, behind, or fully occluded -> not detected.
// Partially visible frames may go either way and are only counted. Prints the confusion table.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "synth.hpp"

namespace netvmo {
namespace {
using namespace io;
using namespace frontend;
using testing::facing_pose;

enum class Geo { visible, small, partial, out_of_view, occluded };
const char* name(Geo g) {
  switch (g) {
    case Geo::visible:
      return "fully visible, side >= 24 px";
    case Geo::small:
      return "fully visible, side < 24 px";
    case Geo::partial:
      return "partly in the image";
    case Geo::out_of_view:
      return "out of view / behind";
    case Geo::occluded:
      return "fully occluded";
  }
  return "?";
}

TEST(Visibility, DetectionAgreesWithGeometry) {
  const auto calib = testing::test_calibration(true);
  const double size = 0.2;
  TagDetector det;
  int table[5][2] = {};
  // The target sweeps sideways through the field of view at several depths and turns; every
  // 7th frame an occluder covers it completely.
  int frame = 0;
  for (double z : {1.0, 2.0, 4.0, 6.0, 9.0})
    for (double x = -2.2; x <= 2.2; x += 0.2, ++frame) {
      const double xs = x * z / 2.0;  // same angular sweep at every depth
      const obs::SE3 g =
          facing_pose(z, xs, 0.1 * std::sin(frame),
                      {0.3 * std::sin(0.7 * frame), 0.25 * std::cos(frame), 0.4 * frame});
      const auto c = testing::project_corners(calib, g, size);
      int inside = 0;
      double side = 1e9;
      double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
      for (size_t k = 0; k < 4; ++k) {
        inside +=
            c[k].x >= 2 && c[k].y >= 2 && c[k].x <= calib.width - 3 && c[k].y <= calib.height - 3;
        side = std::min(side, cv::norm(c[(k + 1) % 4] - c[k]));
        x0 = std::min(x0, c[k].x);
        y0 = std::min(y0, c[k].y);
        x1 = std::max(x1, c[k].x);
        y1 = std::max(y1, c[k].y);
      }
      // quiet zone included: the tag's full printed extent must be inside for "fully visible"
      const double grow = side / 8.0 + 2;
      const cv::Rect2d printed(x0 - grow, y0 - grow, x1 - x0 + 2 * grow, y1 - y0 + 2 * grow);
      const bool all_in = printed.x >= 0 && printed.y >= 0 && printed.br().x <= calib.width - 1 &&
                          printed.br().y <= calib.height - 1;
      // out of view: the whole printed square is off the image (checked on a dense border sample)
      bool any_in = false;
      for (int i = 0; i <= 40 && !any_in; ++i)
        for (int j = 0; j <= 40 && !any_in; ++j) {
          const obs::Vec3 p = g * obs::Vec3(-0.125 + 0.25 * i / 40, -0.125 + 0.25 * j / 40, 0);
          if (p.z() <= 0) continue;
          const auto px = denormalize_points({{p.x() / p.z(), p.y() / p.z()}}, calib)[0];
          any_in = px.x >= -0.5 && px.y >= -0.5 && px.x <= calib.width - 0.5 &&
                   px.y <= calib.height - 0.5;
        }
      testing::SynthSettings opt;
      opt.noise_sigma = 2.0;
      opt.supersample = 2;  // geometry classification only; keeps the sweep fast
      opt.seed = static_cast<std::uint64_t>(frame);
      Geo geo;
      if (!any_in)
        geo = Geo::out_of_view;
      else if (all_in && frame % 7 == 3) {
        geo = Geo::occluded;
        opt.occluders = {cv::Rect(cv::Point(int(printed.x) - 2, int(printed.y) - 2),
                                  cv::Point(int(printed.br().x) + 3, int(printed.br().y) + 3))};
      } else if (all_in && inside == 4)
        geo = side >= 24 ? Geo::visible : Geo::small;
      else
        geo = Geo::partial;
      const cv::Mat img = testing::render_tags(calib, {{0, size, g, {}}}, opt);
      const bool detected = det.detect(img, &calib).status == TargetStatus::detected;
      if (std::getenv("NETVMO_DUMP"))
        cv::imwrite("/tmp/vis_" + std::to_string(frame) + ".png", img);
      ++table[static_cast<int>(geo)][detected];
      if (geo == Geo::visible) {
        EXPECT_TRUE(detected) << "frame " << frame << " z " << z << " side " << side;
      }
      if (geo == Geo::out_of_view || geo == Geo::occluded) {
        EXPECT_FALSE(detected) << "frame " << frame << " " << name(geo);
      }
    }
  std::printf(
      "| geometry (synthetic sweep, 640x480, 2x2 supersampling, distortion, noise 2) | detected | "
      "not detected |\n"
      "|---|---|---|\n");
  for (int gi = 0; gi < 5; ++gi)
    std::printf("| %s | %d | %d |\n", name(static_cast<Geo>(gi)), table[gi][1], table[gi][0]);
  EXPECT_GT(table[0][1], 20);  // the sweep really contains visible frames
  EXPECT_GT(table[3][0], 10);  // and out-of-view ones
  EXPECT_GT(table[4][0], 3);   // and occluded ones
}

}  // namespace
}  // namespace netvmo
