// The border / quiet-zone check of the accepted target on synthesized images with exactly
// known corners: a quad with one side on an occluder's outline (dark or bright occluder) or on
// the image border is rejected as border_mismatch with the failing side in the reason, while
// clean, blurred and shadowed tags are kept, also blurred and gamma-encoded as by a camera (the
// blur discount of the thickness test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/refine.hpp"
#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "netvmo/render/renderer.hpp"
#include "synth.hpp"

namespace netvmo {
namespace {
using namespace io;
using namespace frontend;

constexpr double kSize = 0.2;

DetectorSettings with_check(bool on) {
  DetectorSettings s;
  s.border_check = on;
  return s;
}

using testing::max_corner_error;

/// The thickness test's figures of a check, for failure messages.
std::string describe(const BorderCheck& b) {
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "thickness errors %.2f %.2f %.2f %.2f, expected %.2f %.2f %.2f %.2f, edge bias "
                "x %.2f y %.2f px (%d, %d pairs)",
                b.thickness_error[0], b.thickness_error[1], b.thickness_error[2],
                b.thickness_error[3], b.expected_thickness_error[0], b.expected_thickness_error[1],
                b.expected_thickness_error[2], b.expected_thickness_error[3], b.edge_bias[0],
                b.edge_bias[1], b.edge_bias_pairs[0], b.edge_bias_pairs[1]);
  return buf;
}

/// What realign_and_check() made of the moved sides of expect_moved_sides_rejected().
struct Realignments {
  int kept = 0;        ///< quads kept with the moved side halfway
  double worst = 0.0;  ///< their largest corner error [px]
  double inner = 0.0;  ///< the largest corner error with the side on its inner edge [px]
};

/// A quad of check_moved_sides(): one side of the correct quad moved.
struct MovedSide {
  size_t side = 0;
  double moved = 0.0;                  ///< [px], outward positive
  std::array<cv::Point2d, 4> quad;     ///< as moved
  BorderCheck check;                   ///< check_border() of `quad`
  std::optional<Realigned> realigned;  ///< realign_and_check() where the check rejected `quad`
  /// What the front end would report where it keeps the quad (as moved, or realigned), the
  /// print's edge bias taken off (remove_edge_bias()): its largest corner error from the cell
  /// grid [px]; 0 where it keeps nothing.
  double error = 0.0;
  double inner_error = 0.0;  ///< the same with a realigned side on its inner edge [px]
  bool kept() const { return check.ok || realigned.has_value(); }
};

/// The quads of `img` with one side of the correct quad `c` moved 1 or 1.5 px out or in that put
/// a corner more than 1 px from `truth`, each checked as the front end does (check_border(),
/// then realign_and_check() where it rejects), with errors against the cell grid's corners
/// (`grid`; default `truth`). `measured` (the check of `c`), when given: a side whose thickness
/// it could not measure (no white data cell next to it) is not moved.
std::vector<MovedSide> check_moved_sides(const cv::Mat& img, const std::array<cv::Point2d, 4>& c,
                                         const std::array<cv::Point2d, 4>& truth,
                                         const cv::Mat& pattern, const DetectorSettings& s,
                                         const io::Calibration& calib,
                                         const BorderCheck* measured = nullptr,
                                         const std::array<cv::Point2d, 4>* grid = nullptr) {
  std::vector<MovedSide> out;
  const auto& g = grid ? *grid : truth;
  for (size_t k = 0; k < 4; ++k) {
    if (measured && std::isnan(measured->thickness_error[k])) continue;
    for (double d : {-1.5, -1.0, 1.0, 1.5}) {
      MovedSide m;
      m.side = k;
      m.moved = d;
      m.quad = testing::move_side(c, k, d);
      if (max_corner_error(m.quad, truth) <= 1.0) continue;
      m.check = check_border(img, m.quad, pattern, 8, s, &calib);
      if (m.check.ok) {
        m.error = max_corner_error(remove_edge_bias(m.quad, m.check, &calib), g);
      } else if ((m.realigned = realign_and_check(img, m.quad, m.check, pattern, 8, s, &calib))) {
        const Realigned& r = *m.realigned;
        m.error = max_corner_error(remove_edge_bias(r.corners, r.check, &calib), g);
        m.inner_error = max_corner_error(remove_edge_bias(r.inner, r.check, &calib), g);
      }
      out.push_back(m);
    }
  }
  return out;
}

/// The quads of check_moved_sides() of the correct quad `c`, each expected rejected by the
/// check. Where realign_and_check() keeps one (the moved side back on the border's inner edge),
/// its corners with the print's edge bias taken off must be within 1 px of the cell grid's, and
/// the side on the inner edge nearer `c` than as moved; counted in `realigned` when given.
void expect_rejected(const std::vector<MovedSide>& moved, const std::array<cv::Point2d, 4>& c,
                     const std::string& what, Realignments* realigned = nullptr) {
  for (const MovedSide& m : moved) {
    EXPECT_FALSE(m.check.ok) << what << ", side " << m.side << " moved " << m.moved
                             << " px: " << describe(m.check);
    if (m.check.ok || !m.realigned) continue;
    const Realigned& r = *m.realigned;
    EXPECT_LT(m.error, 1.0) << what << ", side " << m.side << " moved " << m.moved
                            << " px, kept halfway to " << max_corner_error(m.quad, r.inner)
                            << " px off: " << describe(r.check);
    EXPECT_LT(max_corner_error(r.inner, c), max_corner_error(m.quad, c))
        << what << ", side " << m.side << " moved " << m.moved << " px: not moved back";
    if (realigned) {
      ++realigned->kept;
      realigned->worst = std::max(realigned->worst, m.error);
      realigned->inner = std::max(realigned->inner, m.inner_error);
    }
  }
}

/// check_moved_sides() then expect_rejected(); returns how many quads were checked.
int expect_moved_sides_rejected(const cv::Mat& img, const std::array<cv::Point2d, 4>& c,
                                const std::array<cv::Point2d, 4>& truth, const cv::Mat& pattern,
                                const DetectorSettings& s, const io::Calibration& calib,
                                const std::string& what, const BorderCheck* measured = nullptr,
                                Realignments* realigned = nullptr,
                                const std::array<cv::Point2d, 4>* grid = nullptr) {
  const auto moved = check_moved_sides(img, c, truth, pattern, s, calib, measured, grid);
  expect_rejected(moved, c, what, realigned);
  return static_cast<int>(moved.size());
}

/// Multiplies the image by `factor` on the left of the directed line through `p` at angle
/// `angle` (4x4 supersampled, so the shadow edge is a sharp, pixel-integrated straight edge).
void shade(cv::Mat& img, cv::Point2d p, double angle, double factor) {
  const cv::Point2d d(std::cos(angle), std::sin(angle));
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      int in = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          const cv::Point2d q = cv::Point2d(c - 0.5 + (j + 0.5) / 4, r - 0.5 + (i + 0.5) / 4) - p;
          in += q.x * d.y - q.y * d.x < 0;
        }
      uchar& v = img.at<uchar>(r, c);
      v = cv::saturate_cast<uchar>(v * (1.0 - in / 16.0 * (1.0 - factor)));
    }
}

void add_noise(cv::Mat& img, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, sigma);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c)
      img.at<uchar>(r, c) = cv::saturate_cast<uchar>(img.at<uchar>(r, c) + n(rng));
}

/// An occluder of gray `level` covering the image left of the tag's left side + `edge_cells`
/// cells, the tag 1.5 m ahead and rolled by `roll`: its pose, true corners and the image options.
struct OccluderCase {
  double level, roll, edge_cells;
  obs::SE3 pose() const { return testing::facing_pose(1.5, 0.0, 0.0, {0.0, 0.0, roll}); }
  testing::SynthSettings options(const std::array<cv::Point2d, 4>& truth) const {
    const double left = 0.5 * (truth[0].x + truth[3].x), cell = cv::norm(truth[1] - truth[0]) / 8;
    testing::SynthSettings opt;
    opt.occluder_level = level;
    opt.occluders = {cv::Rect(0, 0, static_cast<int>(std::lround(left + edge_cells * cell)), 480)};
    return opt;
  }
  std::array<cv::Point2d, 4> truth(const Calibration& calib) const {
    return testing::project_corners(calib, pose(), kSize);
  }
  /// The tag and the occluder as they are, with noise of 2 gray levels.
  cv::Mat image(const Calibration& calib) const {
    testing::SynthSettings opt = options(truth(calib));
    opt.noise_sigma = 2.0;
    return testing::render_tags(calib, {{0, kSize, pose(), {}}}, opt);
  }
};
// Occluders over part of the border's left cell row: grey, bright grey and nearly the quiet
// zone's white. (A dark one there leaves no tag libapriltag decodes.)
constexpr OccluderCase kOccluderCases[] = {{150, 0.03, 0.2}, {200, 0.06, 0.2}, {170, 0.06, 0.4}};
// Black and dark grey occluders stopping 0.4 cell short of the border, in the quiet zone.
constexpr OccluderCase kShortOccluderCases[] = {{20, 0.03, -0.4}, {90, 0.06, -0.4}};

// An occluder covers part of the tag's left border, its straight edge a few degrees off the
// side, so the left side is fitted to the occluder's outline (a corner 2.7-5.9 px off) and the
// tag is still decoded. Without the check the quad is accepted; with it the frame is
// border_mismatch, and the reason names side 3 (corners 3-0, the left side): the border looks
// thinner there. An occluder that stops short of the border, in the quiet zone, pulled the fit
// onto its outline too (a corner 1.9-2.3 px off) until the fit left out the differences beyond
// the quiet zone's peak (NarrowQuietZoneBeforeSomethingDarkerKeptWrongSideRejected): its quad is
// now the tag's, and the tag is kept, or rejected where the quiet zone half a cell out is dark.
TEST(BorderCheck, QuadOnAnOccludersOutlineRejected) {
  const auto calib = testing::test_calibration();
  for (const OccluderCase& c : kOccluderCases) {
    const auto truth = c.truth(calib);
    const cv::Mat img = c.image(calib);
    const std::string what = "occluder level " + std::to_string(c.level);

    const auto unchecked = TagDetector(with_check(false)).detect(img, &calib);
    ASSERT_EQ(unchecked.status, TargetStatus::detected) << what;
    const double err = max_corner_error(unchecked.target()->corners, truth);
    std::printf("%s: without the check a corner is %.2f px off\n", what.c_str(), err);
    ASSERT_GT(err, 1.5) << what << ": libapriltag did not fit the occluder's edge";

    const auto checked = TagDetector(with_check(true)).detect(img, &calib);
    EXPECT_EQ(checked.status, TargetStatus::border_mismatch) << what;
    EXPECT_EQ(checked.target(), nullptr) << what;
    EXPECT_NE(checked.reason.find("side 3"), std::string::npos) << what << ": " << checked.reason;
    std::printf("  with it: %s: %s\n", to_string(checked.status), checked.reason.c_str());
    // the front end reports the same
    FrontEnd fe;
    const auto o = fe.observe(img, calib);
    EXPECT_FALSE(o.delta);
    EXPECT_EQ(o.status, TargetStatus::border_mismatch);
    EXPECT_EQ(o.reason, checked.reason);
  }
  for (const OccluderCase& c : kShortOccluderCases) {
    const auto truth = c.truth(calib);
    const cv::Mat img = c.image(calib);
    const std::string what = "occluder level " + std::to_string(c.level) + " short of the border";
    const auto unchecked = TagDetector(with_check(false)).detect(img, &calib);
    ASSERT_EQ(unchecked.status, TargetStatus::detected) << what;
    EXPECT_LT(max_corner_error(unchecked.target()->corners, truth), 0.5) << what;
    const auto checked = TagDetector(with_check(true)).detect(img, &calib);
    std::printf("%s: %s %s\n", what.c_str(), to_string(checked.status), checked.reason.c_str());
    if (checked.status == TargetStatus::detected)
      EXPECT_LT(max_corner_error(checked.target()->corners, truth), 0.5) << what;
    else
      EXPECT_NE(checked.reason.find("quiet zone not brighter"), std::string::npos)
          << what << ": " << checked.reason;
  }
}

// The tag's right side 2 px inside the image border: libapriltag closes the quad on the image
// border (corners ~7 px off). The quiet zone beyond that side is outside the image: rejected.
TEST(BorderCheck, QuadOnTheImageBorderRejected) {
  const auto calib = testing::test_calibration();
  const obs::SE3 g = testing::facing_pose(1.2, 0.5175, 0.0, {0.0, 0.0, 0.05});
  const auto truth = testing::project_corners(calib, g, kSize);
  testing::SynthSettings opt;
  opt.noise_sigma = 2.0;
  const cv::Mat img = testing::render_tags(calib, {{0, kSize, g, {}}}, opt);
  const auto unchecked = TagDetector(with_check(false)).detect(img, &calib);
  ASSERT_EQ(unchecked.status, TargetStatus::detected);
  ASSERT_GT(max_corner_error(unchecked.target()->corners, truth), 1.5);
  const auto checked = TagDetector(with_check(true)).detect(img, &calib);
  EXPECT_EQ(checked.status, TargetStatus::border_mismatch);
  EXPECT_NE(checked.reason.find("side 1"), std::string::npos) << checked.reason;
  EXPECT_NE(checked.reason.find("quiet zone"), std::string::npos) << checked.reason;
}

// Tags that are really there are kept: six poses 0.8-3 m (sides 40-150 px, tilted up to 35
// degrees), without and with lens distortion, each clean, blurred (Gaussian sigma 1 and 1.5 px)
// and under a shadow edge through its centre at three angles (the shadowed side at 0.6 of the
// light), all with noise sigma 2. Every one is decoded without the check (so only the check
// is tested), the check runs on it (`checked`) and accepts it.
TEST(BorderCheck, CleanBlurredAndShadowedTagsKept) {
  const std::vector<obs::SE3> poses = {testing::facing_pose(1.0, 0.05, -0.03, {0.3, -0.2, 0.4}),
                                       testing::facing_pose(1.5, -0.2, 0.1, {-0.4, 0.1, 1.2}),
                                       testing::facing_pose(2.0, 0.3, 0.2, {0.2, 0.5, -2.5}),
                                       testing::facing_pose(0.8, -0.1, -0.15, {0.6, 0.0, 0.1}),
                                       testing::facing_pose(2.0, -0.1, 0.05, {-0.3, -0.35, 0.8}),
                                       testing::facing_pose(3.0, 0.1, -0.1, {0.5, 0.3, 0.2})};
  TagDetector unchecked(with_check(false)), checked(with_check(true));
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int n = 0;
  double worst = 0.0;
  for (bool distortion : {false, true}) {
    const auto calib = testing::test_calibration(distortion);
    for (size_t p = 0; p < poses.size(); ++p) {
      const auto truth = testing::project_corners(calib, poses[p], kSize);
      const cv::Point2d centre = 0.25 * (truth[0] + truth[1] + truth[2] + truth[3]);
      const cv::Mat clean = testing::render_tags(calib, {{0, kSize, poses[p], {}}});
      for (int v = 0; v < 6; ++v) {
        cv::Mat img = clean.clone();
        std::string what = "clean";
        if (v == 1 || v == 2) {
          cv::GaussianBlur(img, img, cv::Size(0, 0), v == 1 ? 1.0 : 1.5);
          what = v == 1 ? "blur 1" : "blur 1.5";
        } else if (v >= 3) {
          const double angle = 0.5 + 1.1 * (v - 3);
          shade(img, centre, angle, 0.6);
          what = "shadow edge at " + std::to_string(angle) + " rad";
        }
        add_noise(img, 2.0, static_cast<unsigned>(100 * distortion + 10 * p + v));
        what += (distortion ? ", distortion" : "") + std::string(", pose ") + std::to_string(p);
        const auto a = unchecked.detect(img, &calib);
        ASSERT_EQ(a.status, TargetStatus::detected) << what;
        const BorderCheck bc =
            check_border(img, a.target()->corners, pattern, 8, checked.settings(), &calib);
        EXPECT_TRUE(bc.checked) << what;
        for (double t : bc.thickness_error)
          if (!std::isnan(t)) worst = std::max(worst, std::abs(t));
        const auto b = checked.detect(img, &calib);
        EXPECT_EQ(b.status, TargetStatus::detected) << what << ": " << b.reason;
        EXPECT_TRUE(b.reason.empty()) << what;
        ++n;
      }
    }
  }
  std::printf("%d tags kept; largest inner-edge offset %.2f px (limit %.2f)\n", n, worst,
              DetectorSettings{}.border_max_thickness_error);
  EXPECT_EQ(n, 72);
}

// Point-sampled images (one sample per pixel, as a 1-spp rendering): an upright tag's edges
// are quantised to the pixel grid, so its border's two edges can disagree by up to ~0.8 px on
// a correct quad. The check sees that no pixel on the sides has an intermediate value, flags
// the image as aliased and allows 0.5 px more; the same tags integrated over the pixel (4x4
// samples) are not flagged and stay well inside the strict limit.
TEST(BorderCheck, PointSampledTagsKept) {
  const auto calib = testing::test_calibration();
  TagDetector unchecked(with_check(false)), checked(with_check(true));
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  double worst_point_sampled = 0.0;
  for (int supersample : {1, 4})
    for (double z : {1.0, 1.5, 2.0, 2.5})
      for (double dx : {0.0, 0.013, 0.027, 0.041}) {
        testing::SynthSettings opt;
        opt.supersample = supersample;
        opt.noise_sigma = 2.0;
        const cv::Mat img =
            testing::render_tags(calib, {{0, kSize, testing::facing_pose(z, dx, 0.011), {}}}, opt);
        const std::string what = std::to_string(supersample) + " samples per pixel side, z " +
                                 std::to_string(z) + ", dx " + std::to_string(dx);
        const auto a = unchecked.detect(img, &calib);
        ASSERT_EQ(a.status, TargetStatus::detected) << what;
        const BorderCheck bc =
            check_border(img, a.target()->corners, pattern, 8, checked.settings(), &calib);
        EXPECT_EQ(bc.aliased, supersample == 1) << what;
        for (double t : bc.thickness_error) {
          if (std::isnan(t)) continue;
          if (supersample == 1) {
            worst_point_sampled = std::max(worst_point_sampled, std::abs(t));
          } else {
            EXPECT_LT(std::abs(t), 0.3) << what;
          }
        }
        EXPECT_EQ(checked.detect(img, &calib).status, TargetStatus::detected) << what;
      }
  std::printf("point-sampled: largest inner-edge offset %.2f px\n", worst_point_sampled);
  EXPECT_GT(worst_point_sampled, DetectorSettings{}.border_max_thickness_error);  // not vacuous
}

/// A camera's picture of a print (testing::render_camera_picture): black ink at 5 % of the
/// white (12 of 230), blurred by a Gaussian of `sigma` px in linear light, gamma-encoded as
/// sRGB roughly is (v^(1/2.2)), then sensor noise sigma 2 (seeded).
cv::Mat camera_picture(const io::Calibration& calib, const obs::SE3& g, double sigma,
                       testing::SynthSettings opt, unsigned seed) {
  opt.black = 12.0;
  opt.noise_sigma = 2.0;
  opt.seed = seed;
  return testing::render_camera_picture(calib, {{0, kSize, g, {}}}, opt, sigma);
}

// The tone curve of a camera moves every edge of a blurred print towards the dark side (0.42
// sigma per edge for sRGB and 5 % black ink), so a correct border looks thinner on all four
// sides: on these tags (cells of 5-6 px) blurred by sigma 1 px and gamma-encoded, 0.55-0.8 px,
// and the fixed 0.6 px limit (border_blur_allowance 0) rejects correct quads. The default
// discounts the thinning all sides share, up to the measured blur: every correct quad is
// kept, while the same quads with one measured side moved 1 or 1.5 px (in or out), and a quad
// on a bright or dark occluder's outline in the same picture, are still rejected.
TEST(BorderCheck, BlurredTagThinnedByTheToneCurveKeptWrongSideRejected) {
  const auto calib = testing::test_calibration();
  const std::vector<obs::SE3> poses = {testing::facing_pose(2.5, 0.1, -0.05, {0.2, -0.1, 0.5}),
                                       testing::facing_pose(3.0, -0.15, 0.1, {-0.2, 0.25, -1.0}),
                                       testing::facing_pose(2.5, -0.2, -0.1, {0.1, 0.3, 2.2}),
                                       testing::facing_pose(3.0, 0.2, 0.05, {0.3, 0.1, -2.6})};
  DetectorSettings fixed = with_check(true);
  fixed.border_blur_allowance = 0.0;
  fixed.border_edge_bias = false;
  fixed.border_shared_deviation = false;
  fixed.border_significance = 0.0;
  const DetectorSettings dflt = with_check(true);
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int fixed_rejects = 0, wrong_quads = 0;
  Realignments realigned;
  for (size_t p = 0; p < poses.size(); ++p) {
    const std::string what = "pose " + std::to_string(p);
    const auto truth = testing::project_corners(calib, poses[p], kSize);
    const cv::Mat img = camera_picture(calib, poses[p], 1.0, {}, static_cast<unsigned>(300 + p));
    const auto a = TagDetector(with_check(false)).detect(img, &calib);
    ASSERT_EQ(a.status, TargetStatus::detected) << what;
    const auto& c = a.target()->corners;
    ASSERT_LT(max_corner_error(c, truth), 1.0) << what << ": not a correct quad";
    const BorderCheck bf = check_border(img, c, pattern, 8, fixed, &calib);
    const BorderCheck bd = check_border(img, c, pattern, 8, dflt, &calib);
    std::printf(
        "%s: corners %.2f px off, thickness errors %.2f %.2f %.2f %.2f, blur %.2f px, "
        "discounted %.2f; fixed limit: %s\n",
        what.c_str(), max_corner_error(c, truth), bd.thickness_error[0], bd.thickness_error[1],
        bd.thickness_error[2], bd.thickness_error[3], bd.edge_blur, bd.common_offset,
        bf.ok ? "kept" : bf.reason.c_str());
    fixed_rejects += !bf.ok;
    EXPECT_TRUE(bd.ok) << what << ": " << bd.reason;
    EXPECT_LT(bd.common_offset, 0.0) << what;
    EXPECT_LT(bd.edge_bias[0], 0.0) << what << ": " << describe(bd);  // the tone curve thins
    EXPECT_LT(bd.edge_bias[1], 0.0) << what << ": " << describe(bd);
    EXPECT_EQ(TagDetector(dflt).detect(img, &calib).status, TargetStatus::detected) << what;

    // The same picture, one side of the quad moved along its outward normal.
    wrong_quads +=
        expect_moved_sides_rejected(img, c, truth, pattern, dflt, calib, what, &bd, &realigned);
  }
  EXPECT_GT(fixed_rejects, 0) << "the fixed limit kept every tag: the test shows nothing";
  EXPECT_GT(wrong_quads, 20);
  std::printf(
      "fixed limit rejected %d of %zu correct quads; %d wrong quads checked, %d realigned "
      "(corners within %.2f px, %.2f px with the side on its inner edge)\n",
      fixed_rejects, poses.size(), wrong_quads, realigned.kept, realigned.worst, realigned.inner);

  // A quad on an occluder's outline (the cases of QuadOnAnOccludersOutlineRejected), blurred
  // and encoded the same way.
  for (const OccluderCase& oc : kOccluderCases) {
    const auto truth = oc.truth(calib);
    const cv::Mat img = camera_picture(calib, oc.pose(), 1.0, oc.options(truth), 400);
    const std::string what = "occluder level " + std::to_string(oc.level);
    const auto unchecked = TagDetector(with_check(false)).detect(img, &calib);
    ASSERT_EQ(unchecked.status, TargetStatus::detected) << what;
    const double err = max_corner_error(unchecked.target()->corners, truth);
    std::printf("%s: without the check a corner is %.2f px off\n", what.c_str(), err);
    ASSERT_GT(err, 1.0) << what << ": libapriltag did not fit the occluder's edge";
    const auto checked = TagDetector(dflt).detect(img, &calib);
    EXPECT_EQ(checked.status, TargetStatus::border_mismatch) << what;
    std::printf("  with it: %s\n", checked.reason.c_str());
  }
}

/// A print seen by a camera, as real photos show it: ink spread `spread` cells, motion blur
/// `motion` px over the exposure, optical blur `sigma` px, the sRGB-like tone curve and noise.
struct PrintCase {
  double spread;
  cv::Point2d motion;
  double sigma;
  const char* what;
};

// The real photos' failure (a correct border 0.6-1.0 px thinner or thicker than a cell on one
// axis, hand-held views 50-65 degrees off the tag's normal) reproduced: ink spread of +-0.12
// cell, motion blur along one image axis and the camera's tone curve move every edge of the
// print alike, by a bias b per tag axis. With the bias measured on the tag's own cells
// (default) every correct quad is kept; without it (the fixed limit) correct quads are lost;
// and every quad with one side moved 1 or 1.5 px (in or out) in the same pictures is rejected
// either way.
TEST(BorderCheck, InkSpreadAndMotionBlurKeptWrongSideRejected) {
  const auto calib = testing::test_calibration();
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.6, 0.1, -0.05, {0.2, -0.1, 0.5}),
      testing::facing_pose(2.0, -0.15, 0.1, {-0.2, 0.25, -1.0}),
      testing::facing_pose(1.0, 0.05, 0.0, {1.0, 0.1, 0.3}),       // 57 degrees off the normal
      testing::facing_pose(1.1, -0.05, 0.05, {0.15, -1.05, 2.0}),  // 61 degrees
  };
  const PrintCase cases[] = {
      {0.12, {0, 0}, 0.6, "ink spread +0.12 cell"},
      {-0.12, {0, 0}, 0.6, "ink spread -0.12 cell"},
      {0.0, {3.0, 0.0}, 0.6, "motion blur 3 px along x"},
      {0.0, {0.0, 2.5}, 0.8, "motion blur 2.5 px along y"},
      {0.08, {2.0, 1.0}, 0.7, "ink spread +0.08 cell, motion blur (2, 1) px"},
  };
  DetectorSettings fixed = with_check(true);
  fixed.border_blur_allowance = 0.0;
  fixed.border_edge_bias = false;
  fixed.border_shared_deviation = false;
  fixed.border_significance = 0.0;
  const DetectorSettings dflt = with_check(true);
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int correct = 0, fixed_rejects = 0, wrong_quads = 0, wrong_kept_fixed = 0;
  Realignments realigned;
  for (const PrintCase& pc : cases)
    for (size_t p = 0; p < poses.size(); ++p) {
      const std::string what = std::string(pc.what) + ", pose " + std::to_string(p);
      testing::SynthSettings opt;
      opt.black = 12.0;
      opt.noise_sigma = 2.0;
      opt.seed = static_cast<unsigned>(500 + p);
      opt.ink_spread = pc.spread;
      opt.motion_blur = pc.motion;
      const cv::Mat img =
          testing::render_camera_picture(calib, {{0, kSize, poses[p], {}}}, opt, pc.sigma);
      // The printed black square is the nominal one grown by the spread on every side.
      const auto truth = testing::project_corners(calib, poses[p], kSize * (1 + 2 * pc.spread / 8));
      const auto a = TagDetector(with_check(false)).detect(img, &calib);
      ASSERT_EQ(a.status, TargetStatus::detected) << what;
      const auto& c = a.target()->corners;
      ASSERT_LT(max_corner_error(c, truth), 1.0) << what << ": not a correct quad";
      const BorderCheck bf = check_border(img, c, pattern, 8, fixed, &calib);
      const BorderCheck bd = check_border(img, c, pattern, 8, dflt, &calib);
      std::printf(
          "%s: corners %.2f px off, thickness errors %.2f %.2f %.2f %.2f, edge bias x %.2f y "
          "%.2f px; fixed limit: %s\n",
          what.c_str(), max_corner_error(c, truth), bd.thickness_error[0], bd.thickness_error[1],
          bd.thickness_error[2], bd.thickness_error[3], bd.edge_bias[0], bd.edge_bias[1],
          bf.ok ? "kept" : bf.reason.c_str());
      ++correct;
      fixed_rejects += !bf.ok;
      EXPECT_TRUE(bd.ok) << what << ": " << bd.reason;
      EXPECT_FALSE(std::isnan(bd.edge_bias[0]) || std::isnan(bd.edge_bias[1])) << what;
      EXPECT_EQ(TagDetector(dflt).detect(img, &calib).status, TargetStatus::detected) << what;

      for (size_t k = 0; k < 4; ++k) {
        if (std::isnan(bd.thickness_error[k])) continue;  // no white data cell next to it
        for (double d : {-1.5, -1.0, 1.0, 1.5}) {
          const auto w = testing::move_side(c, k, d);
          if (max_corner_error(w, truth) <= 1.0) continue;
          wrong_kept_fixed += check_border(img, w, pattern, 8, fixed, &calib).ok;
        }
      }
      const auto grid = testing::project_corners(calib, poses[p], kSize);
      wrong_quads += expect_moved_sides_rejected(img, c, truth, pattern, dflt, calib, what, &bd,
                                                 &realigned, &grid);
    }
  std::printf(
      "fixed limit rejected %d of %d correct quads; %d wrong quads, %d kept by it; %d realigned "
      "(corners within %.2f px, %.2f px with the side on its inner edge)\n",
      fixed_rejects, correct, wrong_quads, wrong_kept_fixed, realigned.kept, realigned.worst,
      realigned.inner);
  EXPECT_GT(fixed_rejects, 0) << "the fixed limit kept every tag: the test shows nothing";
  EXPECT_GT(wrong_quads, 100);
}

// The rotation series of the corpus (docs/frontend.md, "Resampled images"): a wide-angle
// camera's frames rectified to a pinhole at a magnification of about 1.65, the nearest
// source pixel taken for each output pixel. That moves each edge of the print by up to half a
// source pixel, independently at the border's outer and inner edges and alike along a side that
// runs along the source's rows or columns. Made here: a tag pictured through lens distortion (k1
// -0.12 and -0.3), blurred, with the tone curve, noise and JPEG at quality 80, then rectified at
// magnifications 1, 1.3 and 1.65, by nearest neighbour and bilinearly. Every correct quad the
// front end keeps has its corners within 1 px of the rectified camera's truth. Bilinear: every
// quad of the same pictures with one side moved 1 or 1.5 px (a corner more than 1 px off) is
// rejected, or kept halfway back within 1 px. Nearest neighbour: the check's own measurements
// are off by as much as such a move, and it keeps some of those quads; they are counted and
// printed, the limit docs/frontend.md states, not asserted away.
TEST(BorderCheck, RectifiedImagesKeptWithin1PxWrongSideRejectedUnlessNearestNeighbour) {
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.4, 0.35, 0.2, {0.2, -0.1, 0.5}),
      testing::facing_pose(1.6, -0.4, -0.25, {-0.2, 0.5, -1.0}),
      testing::facing_pose(1.2, 0.3, -0.2, {0.7, 0.1, 0.3}),     // 41 degrees off the normal
      testing::facing_pose(1.3, -0.3, 0.2, {0.15, -0.85, 2.0}),  // 50 degrees
  };
  const DetectorSettings dflt = with_check(true);
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  struct Count {
    int pictures = 0, kept = 0;
    double worst = 0.0;  ///< of the kept correct quads' corners [px]
    int wrong = 0;       ///< quads with a side moved
    int wrong_kept = 0;  ///< of them kept (as they are or halfway back), a corner > 1 px off
    double wrong_worst = 0.0;
  };
  Count counts[2];  // nearest, bilinear
  Realignments realigned;
  for (const double k1 : {-0.12, -0.3})
    for (size_t p = 0; p < poses.size(); ++p) {
      io::Calibration raw = testing::test_calibration();
      raw.dist = {k1, 0.05, 4e-4, -3e-4, 0.0};
      testing::SynthSettings opt;
      opt.black = 12.0;
      opt.noise_sigma = 2.0;
      opt.seed = static_cast<unsigned>(900 + p);
      cv::Mat picture = testing::render_camera_picture(raw, {{0, kSize, poses[p], {}}}, opt, 0.6);
      std::vector<uchar> jpeg;
      cv::imencode(".jpg", picture, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
      picture = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
      for (const double m : {1.0, 1.3, 1.65})
        for (const int interpolation : {cv::INTER_NEAREST, cv::INTER_LINEAR}) {
          const bool nearest = interpolation == cv::INTER_NEAREST;
          char what[96];
          std::snprintf(what, sizeof what, "k1 %.2f, pose %zu, magnification %.2f, %s", k1, p, m,
                        nearest ? "nearest" : "bilinear");
          const testing::Rectified r = testing::rectify(picture, raw, m, interpolation);
          const auto truth = testing::project_corners(r.calib, poses[p], kSize);
          const auto a = TagDetector(with_check(false)).detect(r.image, &r.calib);
          if (a.status != TargetStatus::detected) {
            std::printf("%s: not decoded\n", what);
            continue;
          }
          const auto& c = a.target()->corners;
          if (max_corner_error(c, truth) >= 1.0) {  // no correct quad to check
            std::printf("%s: the edge fit's corners %.2f px off\n", what,
                        max_corner_error(c, truth));
            continue;
          }
          Count& n = counts[nearest ? 0 : 1];
          ++n.pictures;
          const auto b = TagDetector(dflt).detect(r.image, &r.calib);
          if (b.status == TargetStatus::detected) {
            ++n.kept;
            const double e = max_corner_error(b.target()->corners, truth);
            n.worst = std::max(n.worst, e);
            EXPECT_LT(e, 1.0) << what;
          } else {
            std::printf("%s: rejected, %s\n", what, b.reason.c_str());
          }
          const BorderCheck bd = check_border(r.image, c, pattern, 8, dflt, &r.calib);
          const auto moved = check_moved_sides(r.image, c, truth, pattern, dflt, r.calib, &bd);
          if (!nearest)  // each rejected, or realigned within 1 px and nearer the correct quad
            expect_rejected(moved, c, what, &realigned);
          n.wrong += static_cast<int>(moved.size());
          for (const MovedSide& w : moved)  // nearest neighbour: counted, not asserted
            if (w.kept() && w.error > 1.0) {
              ++n.wrong_kept;
              n.wrong_worst = std::max(n.wrong_worst, w.error);
            }
        }
    }
  for (int i = 0; i < 2; ++i)
    std::printf(
        "%s: %d of %d correct quads kept (corners within %.2f px); of %d quads with a side "
        "moved, %d kept with a corner more than 1 px off (up to %.2f px)\n",
        i == 0 ? "nearest" : "bilinear", counts[i].kept, counts[i].pictures, counts[i].worst,
        counts[i].wrong, counts[i].wrong_kept, counts[i].wrong_worst);
  std::printf("bilinear: %d moved quads kept halfway back (corners within %.2f px)\n",
              realigned.kept, realigned.worst);
  for (const Count& n : counts) {
    EXPECT_GT(n.pictures, 16);
    EXPECT_GT(n.wrong, 100);
  }
}

// The real photos' other failure made by the synthesizer: a print whose black border is
// thinner or thicker than its data cells on every side (the printer's rounding of the bitmap,
// toner, a relief print's walls, resampling), in linear light and under the tone curve, at
// three poses up to 61 degrees off the normal. The print's model of the cells (edge bias) does not
// explain it: without the shared deviation every such tag is rejected; with it every one is kept,
// and every quad of the same pictures with one side moved 1 or 1.5 px (a corner more than 1 px off)
// is still rejected, because one side then deviates alone.
TEST(BorderCheck, BorderThinnerOrThickerThanACellOnEverySideKeptWrongSideRejected) {
  const auto calib = testing::test_calibration();
  // At 57 degrees with the tilt about the tag's x axis (InkSpreadAndMotionBlur's third pose)
  // the sides' deviations, in cells, differ by 0.03 cell and the least deviating one
  // underestimates the print's: that tag is rejected (docs/frontend.md, known limits).
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.6, 0.1, -0.05, {0.2, -0.1, 0.5}),
      testing::facing_pose(2.0, -0.15, 0.1, {-0.2, 0.25, -1.0}),
      testing::facing_pose(1.1, -0.05, 0.05, {0.15, -1.05, 2.0}),  // 61 degrees
  };
  DetectorSettings unshared = with_check(true);
  unshared.border_shared_deviation = false;
  const DetectorSettings dflt = with_check(true);
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int correct = 0, unshared_rejects = 0, wrong_quads = 0;
  Realignments realigned;
  for (double width : {0.88, 1.12})
    for (double gamma : {1.0, 2.2})
      for (size_t p = 0; p < poses.size(); ++p) {
        const std::string what = "border " + std::to_string(width) + " cell, gamma " +
                                 std::to_string(gamma) + ", pose " + std::to_string(p);
        testing::SynthSettings opt;
        opt.black = 12.0;
        opt.noise_sigma = 2.0;
        opt.seed = static_cast<unsigned>(700 + p);
        opt.border_width = width;
        const cv::Mat img =
            testing::render_camera_picture(calib, {{0, kSize, poses[p], {}}}, opt, 0.6, gamma);
        const auto truth = testing::project_corners(calib, poses[p], kSize);
        const auto a = TagDetector(with_check(false)).detect(img, &calib);
        ASSERT_EQ(a.status, TargetStatus::detected) << what;
        const auto& c = a.target()->corners;
        ASSERT_LT(max_corner_error(c, truth), 1.0) << what << ": not a correct quad";
        const BorderCheck bu = check_border(img, c, pattern, 8, unshared, &calib);
        const BorderCheck bd = check_border(img, c, pattern, 8, dflt, &calib);
        std::printf(
            "%s: corners %.2f px off, thickness errors %.2f %.2f %.2f %.2f, shared %.3f cell; "
            "without it: %s\n",
            what.c_str(), max_corner_error(c, truth), bd.thickness_error[0], bd.thickness_error[1],
            bd.thickness_error[2], bd.thickness_error[3], bd.shared_deviation,
            bu.ok ? "kept" : bu.reason.c_str());
        ++correct;
        unshared_rejects += !bu.ok;
        EXPECT_TRUE(bd.ok) << what << ": " << bd.reason;
        EXPECT_EQ(bd.shared_deviation < 0.0, width < 1.0) << what << ": " << describe(bd);
        EXPECT_EQ(TagDetector(dflt).detect(img, &calib).status, TargetStatus::detected) << what;
        wrong_quads +=
            expect_moved_sides_rejected(img, c, truth, pattern, dflt, calib, what, &bd, &realigned);
      }
  std::printf(
      "without the shared deviation %d of %d correct quads rejected; %d wrong quads, %d "
      "realigned (corners within %.2f px, %.2f px with the side on its inner edge)\n",
      unshared_rejects, correct, wrong_quads, realigned.kept, realigned.worst, realigned.inner);
  EXPECT_GT(unshared_rejects, correct / 2) << "the print's border passes without the model";
  EXPECT_GT(wrong_quads, 60);
}

// The rotation series' failure made by the synthesizer: a print whose black border is thinner or
// thicker on one side only (trimmed, misregistered), its outer edge and cells where the bitmap
// puts them. That side alone deviates, as a side on an occluder's outline does, and the check
// rejects many such tags; one picture cannot tell the two apart. realign_and_check() keeps them
// with that side halfway between its outer edge and one cell outside its inner edge, so the
// front end's corners lie within half the side's deviation of the print's whichever is true:
// every corner kept within 1 px of the nominal square, and a tag rejected only where its
// side's deviation moves a corner by more than border_realign_max.
TEST(BorderCheck, BorderThinOrThickOnOneSideKeptHalfway) {
  const auto calib = testing::test_calibration();
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.6, 0.1, -0.05, {0.2, -0.1, 0.5}),
      testing::facing_pose(1.2, 0.05, 0.02, {0.0, 0.6, 0.0}),
      testing::facing_pose(1.1, -0.05, 0.05, {0.15, -1.05, 2.0}),  // 61 degrees
  };
  const DetectorSettings dflt = with_check(true);
  DetectorSettings off = dflt;
  off.border_realign_max = 0.0;
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int pictures = 0, rejected_without = 0, kept = 0;
  double worst = 0.0;
  for (size_t p = 0; p < poses.size(); ++p)
    for (const double gamma : {1.0, 2.2})
      for (size_t edge = 0; edge < 4; ++edge)
        for (const double width : {0.94, 1.06}) {
          char what[120];
          std::snprintf(what, sizeof what, "pose %zu, gamma %.1f, border %.2f cell on edge %zu", p,
                        gamma, width, edge);
          testing::SynthSettings opt;
          opt.black = 12.0;
          opt.noise_sigma = 2.0;
          opt.seed = static_cast<unsigned>(900 + p);
          opt.border_width_per_edge[edge] = width;
          const cv::Mat img =
              testing::render_camera_picture(calib, {{0, kSize, poses[p], {}}}, opt, 0.6, gamma);
          const auto truth = testing::project_corners(calib, poses[p], kSize);
          ++pictures;
          const auto without = TagDetector(off).detect(img, &calib);
          rejected_without += without.status == TargetStatus::border_mismatch;
          const auto a = TagDetector(dflt).detect(img, &calib);
          if (a.status != TargetStatus::detected) {
            // Rejected only where the side's deviation moves a corner further than
            // border_realign_max (a deviation in cells grows with the cells, and at 61 degrees
            // a corner moves further than its side).
            const auto fit = TagDetector(with_check(false)).detect(img, &calib);
            ASSERT_EQ(fit.status, TargetStatus::detected) << what;
            const auto& c = fit.target()->corners;
            const BorderCheck bc = check_border(img, c, pattern, 8, dflt, &calib);
            const auto inner = realign_sides(c, bc, 8, dflt, 1.0, &calib);
            ASSERT_TRUE(inner) << what << ": " << a.reason << "; " << describe(bc);
            EXPECT_GT(max_corner_error(*inner, c), dflt.border_realign_max)
                << what << ": " << a.reason;
            continue;
          }
          ++kept;
          const double e = max_corner_error(a.target()->corners, truth);
          worst = std::max(worst, e);
          EXPECT_LT(e, 1.0) << what;
          if (without.status == TargetStatus::detected) {  // not realigned: the same corners
            EXPECT_LT(max_corner_error(a.target()->corners, without.target()->corners), 1e-9)
                << what;
          }
        }
  std::printf(
      "%d pictures: %d rejected without the realignment, %d kept with it, corners within %.2f "
      "px\n",
      pictures, rejected_without, kept, worst);
  EXPECT_GE(rejected_without, 8) << "the one-sided border no longer fails the check: the test "
                                    "shows nothing";
  EXPECT_GE(kept, pictures - rejected_without + 8) << "fewer than 8 rejections undone";
}

// undecided_covariance(): the midpoint of two explanations a and b, each with weight 1/2, has
// the covariance v v^T with v = (b - a) / 2 stacked (x0, y0, ..., x3, y3).
TEST(BorderCheck, UndecidedCovarianceIsTheHalfDifferencesOuterProduct) {
  const std::array<cv::Point2d, 4> a{{{10, 20}, {30, 20}, {30, 40}, {10, 40}}};
  std::array<cv::Point2d, 4> b = a;
  b[1] += cv::Point2d(1.0, -0.5);
  b[2] += cv::Point2d(0.6, 0.2);
  const CornerCovariance c = undecided_covariance(a, b);
  // The variance of a uniform choice between a and b about their mean, per coordinate pair.
  Eigen::Matrix<double, 8, 1> v = Eigen::Matrix<double, 8, 1>::Zero();
  v(2) = 0.5, v(3) = -0.25, v(4) = 0.3, v(5) = 0.1;
  EXPECT_LT((c - v * v.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(c(2, 2), 0.25, 1e-12);  // (1 - 0)^2 / 4: half the distance, squared
  EXPECT_NEAR(c(2, 4), 0.15, 1e-12);  // both corners of the side move together
  EXPECT_NEAR(c(0, 0), 0.0, 1e-12);
}

// The corners of the print's cell grid: ink spread (the black grown by +-0.12 cell) and a
// camera's tone curve on a blurred print move the black border's outer edges, so the fitted
// quad is the cell grid's dilated by the edge bias, and PnP's distance is off by 2 b / side.
// With the bias the check measured on the cells taken off each side (remove_edge_bias), the
// front end's corners are the nominal square's; without it they are the inked outline's.
TEST(BorderCheck, EdgeBiasRemovedCornersAreTheCellGrids) {
  const auto calib = testing::test_calibration();
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.6, 0.1, -0.05, {0.2, -0.1, 0.5}),
      testing::facing_pose(1.0, 0.05, 0.0, {1.0, 0.1, 0.3}),  // 57 degrees off the normal
      testing::facing_pose(2.0, -0.15, 0.1, {-0.2, 0.25, -1.0}),
  };
  struct Case {
    double spread, sigma, gamma;
    const char* what;
  };
  const Case cases[] = {{0.12, 0.6, 1.0, "ink spread +0.12 cell"},
                        {-0.12, 0.6, 1.0, "ink spread -0.12 cell"},
                        {0.0, 1.2, 2.2, "blur 1.2 px under the tone curve"}};
  DetectorSettings fitted = with_check(true);
  fitted.correct_edge_bias = false;
  const DetectorSettings dflt = with_check(true);
  for (const Case& c : cases) {
    double worst_fitted = 0.0;
    for (size_t p = 0; p < poses.size(); ++p) {
      const std::string what = std::string(c.what) + ", pose " + std::to_string(p);
      testing::SynthSettings opt;
      opt.black = 12.0;
      opt.noise_sigma = 2.0;
      opt.seed = static_cast<unsigned>(900 + p);
      opt.ink_spread = c.spread;
      const cv::Mat img =
          testing::render_camera_picture(calib, {{0, kSize, poses[p], {}}}, opt, c.sigma, c.gamma);
      const auto nominal = testing::project_corners(calib, poses[p], kSize);
      const auto a = TagDetector(dflt).detect(img, &calib);
      const auto b = TagDetector(fitted).detect(img, &calib);
      ASSERT_EQ(a.status, TargetStatus::detected) << what << ": " << a.reason;
      ASSERT_EQ(b.status, TargetStatus::detected) << what << ": " << b.reason;
      const double e_grid = max_corner_error(a.target()->corners, nominal);
      const double e_fitted = max_corner_error(b.target()->corners, nominal);
      std::printf("%s: corners from the nominal square %.2f px (fitted outline %.2f px)\n",
                  what.c_str(), e_grid, e_fitted);
      EXPECT_LT(e_grid, 0.3) << what;
      worst_fitted = std::max(worst_fitted, e_fitted);
    }
    EXPECT_GT(worst_fitted, 0.5) << c.what << ": the outline is not off, the test shows nothing";
  }
}

// A quiet zone cut short: the white margin beyond the black border only 0.15-0.35 cell wide
// before something darker (the card's edge, a dark mount or background; here an image region
// above the tag at two gray levels). The band's far edge, a bright-to-dark step within the
// edge fit's window, pulled the fitted outer edge inward: 1.1-2.5 px at blur 0.7 px, the
// corners that far off and the tag rejected as border_mismatch (side 2, the top, "thinner than
// one cell"). The fit now leaves out the differences beyond the band's peak (edge_offset's
// stop_at_peak): at blur 0.7 px every tag libapriltag finds is kept with its fitted corners
// within 1 px; at 1.3 px bands narrower than the blur are still rejected. Every accepted tag's
// corners are within 1 px of the truth, and every quad of the same pictures with one side moved
// 1 or 1.5 px (a corner more than 1 px off) is rejected.
TEST(BorderCheck, NarrowQuietZoneBeforeSomethingDarkerKeptWrongSideRejected) {
  const auto calib = testing::test_calibration();
  const std::vector<obs::SE3> poses = {
      testing::facing_pose(1.2, 0.0, 0.0),
      testing::facing_pose(1.2, 0.05, 0.02, {0.0, 0.6, 0.0}),  // turned about the vertical
      testing::facing_pose(1.6, -0.05, 0.02, {0.0, -0.9, 0.0}),
      testing::facing_pose(2.5, 0.0, 0.0, {0.0, 0.3, 0.0}),
  };
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  const DetectorSettings dflt = with_check(true);
  int detected = 0, kept = 0, wrong_quads = 0;
  Realignments realigned;
  for (size_t p = 0; p < poses.size(); ++p)
    for (const double level : {40.0, 110.0})
      for (const double sigma : {0.7, 1.3})
        for (const double q : {0.15, 0.25, 0.35}) {
          char what[120];
          std::snprintf(what, sizeof what,
                        "pose %zu, surround %.0f, blur %.1f px, margin %.2f cell", p, level, sigma,
                        q);
          const auto truth = testing::project_corners(calib, poses[p], kSize);
          double top = 1e9, left = 1e9, right = -1e9;
          for (const auto& c : truth) {
            top = std::min(top, c.y);
            left = std::min(left, c.x);
            right = std::max(right, c.x);
          }
          const double cell = (right - left) / 8.0;
          testing::SynthSettings opt;
          opt.black = 12.0;
          opt.background = 200.0;
          opt.noise_sigma = 1.5;
          opt.seed = 7;
          opt.occluder_level = level;  // everything above the margin
          opt.occluders = {cv::Rect(0, 0, calib.width, static_cast<int>(top - q * cell) + 1)};
          const cv::Mat img =
              testing::render_camera_picture(calib, {{0, kSize, poses[p], {}}}, opt, sigma);
          const auto fit = TagDetector(with_check(false)).detect(img, &calib);
          if (fit.status != TargetStatus::detected) continue;  // libapriltag did not find it
          ++detected;
          const auto& c = fit.target()->corners;
          const auto a = TagDetector(dflt).detect(img, &calib);
          const bool ok = a.status == TargetStatus::detected;
          std::printf("%s: fitted corners %.2f px off; %s\n", what, max_corner_error(c, truth),
                      ok ? "kept" : a.reason.c_str());
          if (sigma < 1.0) {
            EXPECT_LT(max_corner_error(c, truth), 1.0) << what << ": the fit is pulled";
            EXPECT_TRUE(ok) << what << ": " << a.reason;
          }
          if (!ok) continue;
          ++kept;
          EXPECT_LT(max_corner_error(a.target()->corners, truth), 1.0) << what;
          // Moved sides of a correct quad only (a fit pulled by the blur, kept realigned, is not).
          if (max_corner_error(c, truth) >= 1.0) continue;
          wrong_quads += expect_moved_sides_rejected(img, c, truth, pattern, dflt, calib, what,
                                                     nullptr, &realigned);
        }
  std::printf(
      "%d of %d tags found kept; %d wrong quads, %d realigned (corners within %.2f px, %.2f px "
      "with the side on its inner edge)\n",
      kept, detected, wrong_quads, realigned.kept, realigned.worst, realigned.inner);
  EXPECT_GE(detected, 40);
  EXPECT_GT(wrong_quads, 100);
}

// Families without a black border ring inside a white one are not checked.
TEST(BorderCheck, ReversedBorderFamilyNotChecked) {
  const cv::Mat pattern = tag_pattern("tagStandard41h12", 0);
  ASSERT_FALSE(pattern.empty());
  const cv::Mat img(480, 640, CV_8UC1, cv::Scalar(128));
  const std::array<cv::Point2d, 4> quad{{{300, 260}, {340, 260}, {340, 220}, {300, 220}}};
  const BorderCheck bc = check_border(img, quad, pattern, 5, DetectorSettings{});
  EXPECT_FALSE(bc.checked);
  EXPECT_TRUE(bc.ok);
  EXPECT_TRUE(tag_pattern("tag36h11", 100000).empty());  // id outside the family
}

// Poses of the bent-card tests: up to 57 degrees off the normal, 0.8-1.6 m away.
const std::vector<obs::SE3> kBentPoses = {
    testing::facing_pose(1.2, 0.0, 0.0, {0.1, -0.1, 0.2}),
    testing::facing_pose(1.6, 0.1, -0.05, {0.2, -0.1, 0.5}),
    testing::facing_pose(1.0, 0.05, 0.0, {1.0, 0.1, 0.3}),
    testing::facing_pose(1.1, -0.05, 0.05, {0.15, -1.05, 2.0}),
    testing::facing_pose(0.8, 0.0, 0.0, {0.0, 0.3, 1.2}),
};

/// One bent tag at kBentPoses[pose] and a camera's picture of it (blur 0.6 px, noise 2 gray
/// levels, encoded with `gamma`), with its true corners.
struct BentCase {
  std::string what;
  cv::Mat img;
  std::array<cv::Point2d, 4> truth;
};
BentCase bent_case(const io::Calibration& calib, size_t pose, double bend, double gamma,
                   unsigned seed) {
  testing::SynthTag tag{0, kSize, kBentPoses[pose], {}};
  tag.bend = bend;
  testing::SynthSettings opt;
  opt.black = 12.0;
  opt.noise_sigma = 2.0;
  opt.seed = seed;
  return {"bend " + std::to_string(bend) + "/m, pose " + std::to_string(pose),
          testing::render_camera_picture(calib, {tag}, opt, 0.6, gamma),
          testing::project_corners(calib, tag)};
}

// A card bent as a sheet curls off a wall (SynthTag::bend, about the tag's y axis): the sides
// along the bend bow in the image, and the straight sides fitted to them meet away from the
// print's corners (a real photo's case: the curled sheet of swatbotics_hallway/IMG_0613.jpg,
// docs/frontend.md). The thickness test rejects most such quads, but not all: without the bow
// test cards bent to radii of 0.25-0.33 m are accepted with a corner 1.01-1.38 px off. With it
// every accepted bent card has its corners within 1 px of the print's: the mildly bent ones (a
// bow moving a corner by about 0.65 px) are kept as they are, and those whose straight sides
// miss the corners by more than border_max_bow are rejected as bowed unless checked again as a
// bent print (DetectorSettings::border_max_bent: the border sampled along the bowed sides) and
// kept with the bow taken off.
TEST(BorderCheck, BentCardWithCornersOffRejectedOrKeptAsBentWithin1Px) {
  const auto calib = testing::test_calibration();
  const DetectorSettings dflt;
  DetectorSettings no_bent = dflt;  // the straight sides' check alone
  no_bent.border_max_bent = 0.0;
  DetectorSettings no_bow = no_bent;
  no_bow.border_max_bow = 0.0;
  int decoded = 0, kept = 0, bowed = 0, bent = 0, off_kept_without = 0;
  double worst_bent = 0.0;
  for (const double bend : {2.0, -2.0, 3.0, -3.0, 4.0, -4.0, 5.0, -5.0, 6.0, -6.0})
    for (size_t p = 0; p < kBentPoses.size(); ++p) {
      const auto [what, img, truth] =
          bent_case(calib, p, bend, 2.2, static_cast<unsigned>(700 + p));
      const FrameDetections d = TagDetector(dflt).detect(img, &calib);
      const FrameDetections ds = TagDetector(no_bent).detect(img, &calib);
      const FrameDetections dn = TagDetector(no_bow).detect(img, &calib);
      if (d.status == TargetStatus::detected) {
        ++decoded, ++kept;
        const double e = max_corner_error(d.target()->corners, truth);
        EXPECT_LE(e, 1.0) << what;
        if (ds.status == TargetStatus::detected) {
          // The bent print's check only adds tags: those the straight sides keep are unchanged.
          EXPECT_EQ(max_corner_error(d.target()->corners, ds.target()->corners), 0.0) << what;
        } else {
          ++bent, worst_bent = std::max(worst_bent, e);
          std::printf("%s: kept as a bent print, corners within %.2f px (straight sides: %s)\n",
                      what.c_str(), e, ds.reason.c_str());
        }
      } else {
        EXPECT_NE(ds.status, TargetStatus::detected) << what;
        decoded += d.status == TargetStatus::border_mismatch;
      }
      bowed += ds.status == TargetStatus::border_mismatch &&
               ds.reason.find("bowed") != std::string::npos;
      if (dn.status == TargetStatus::detected &&
          max_corner_error(dn.target()->corners, truth) > 1.0) {
        ++off_kept_without;
        std::printf("%s: without the bow test kept with a corner %.2f px off; %s\n", what.c_str(),
                    max_corner_error(dn.target()->corners, truth), d.reason.c_str());
      }
    }
  std::printf(
      "%d decoded, %d kept (%d as bent prints, corners within %.2f px); the straight sides' "
      "check rejected %d as bowed; without the bow test %d kept more than 1 px off\n",
      decoded, kept, bent, worst_bent, bowed, off_kept_without);
  EXPECT_GT(off_kept_without, 0) << "no bent card fools the other tests: this one shows nothing";
  EXPECT_GT(bowed, 0);
  EXPECT_GT(bent, 0) << "no card the straight sides reject is kept as a bent print";
  EXPECT_GE(kept - bent, 4) << "the mildly bent cards (2/m at poses 0 and 1) are lost";
}

// A tag printed as `print` at g_co, rendered by the Embree renderer: a camera with the test
// calibration at the origin, gamma 2.2, PSF 0.6 px, sensor noise seeded by `seed`.
struct RenderedCase {
  std::string what;
  cv::Mat img;
  std::array<cv::Point2d, 4> truth;
};
RenderedCase rendered_case(const io::Calibration& calib, const obs::SE3& g_co,
                           const render::PrintModel& print, unsigned seed, std::string what) {
  render::SceneDescription s;
  render::CameraSpec cam;
  cam.intrinsics.width = calib.width;
  cam.intrinsics.height = calib.height;
  cam.intrinsics.fx = calib.K(0, 0);
  cam.intrinsics.fy = calib.K(1, 1);
  cam.intrinsics.cx = calib.K(0, 2);
  cam.intrinsics.cy = calib.K(1, 2);
  cam.sensor.tone = render::SensorModel::Tone::Gamma;
  cam.sensor.psf_sigma = 0.6;
  s.cameras.push_back(cam);
  s.target().tag.id = 0;
  s.target().tag.size = kSize;
  s.target().tag.print = print;
  s.target().motion = render::Trajectory::fixed(g_co);  // the camera is at the origin
  s.lights.front().direction = render::Vec3(0.3, 0.2, 1.0);
  s.imaging.spp = 9;
  s.imaging.seed = seed;  // the sensor's noise
  render::Renderer r(s);
  RenderedCase out{std::move(what), r.render(0, 0), {}};
  const render::FrameTruth t = r.truth(0, 0);
  for (size_t k = 0; k < 4; ++k) out.truth[k] = cv::Point2d(t.corners[k]->x(), t.corners[k]->y());
  return out;
}

// The bent cards of kBentPoses rendered (render::PrintModel::bend: the card's mesh wrapped on
// the cylinder, its texture looked up by arc length).
RenderedCase rendered_bent_case(const io::Calibration& calib, size_t pose, double bend) {
  render::PrintModel print;
  print.bend = bend;
  return rendered_case(
      calib, kBentPoses[pose], print, static_cast<unsigned>(40 + pose),
      "rendered, bend " + std::to_string(bend) + "/m, pose " + std::to_string(pose));
}

// The renderer's bent cards, where the truth is known: its truth corners are the synthesizer's
// (two implementations of the same cylinder); the check measures the bow the renderer made
// (every accepted card's corners moved by the measured shift lie within 0.35 px of the truth:
// measured at most 0.30 px); strongly bent cards are rejected as bowed; and every card kept has
// its corners within 1 px of the print's. That needs the bow taken off: gently bent cards seen
// far off their normal (0.5 /m at 57-60 deg) bow their sides by 0.8-0.99 px, under
// border_max_bow, and with their corners where the straight sides meet 3 of them are kept up
// to 1.10 px off.
TEST(BorderCheck, RenderedBentCardsAreTheSynthesizersAndKeptOnesWithin1Px) {
  const auto calib = testing::test_calibration();
  DetectorSettings no_bent;  // the straight sides' check alone
  no_bent.border_max_bent = 0.0;
  DetectorSettings straight = no_bent;  // the corners where the straight sides meet
  straight.border_bow_correction = 0.0;
  DetectorSettings unrealigned = no_bent;
  unrealigned.border_realign_max = 0.0;
  int kept = 0, measured = 0, bowed = 0, taken_off = 0, off_straight = 0, realigned = 0, bent = 0,
      inner_measured = 0;
  double worst_moved = 0.0, worst = 0.0, worst_straight = 0.0, worst_bent = 0.0, worst_inner = 0.0;
  for (const double bend : {0.5, -0.5, 1.0, -1.0, 2.0, -2.0, 3.0, -3.0, 4.0, -4.0})
    for (size_t p = 0; p < kBentPoses.size(); ++p) {
      const auto c = rendered_bent_case(calib, p, bend);
      testing::SynthTag tag{0, kSize, kBentPoses[p], {}};
      tag.bend = bend;
      EXPECT_LT(max_corner_error(c.truth, testing::project_corners(calib, tag)), 1e-9) << c.what;
      const FrameDetections dflt = TagDetector().detect(c.img, &calib);
      const FrameDetections d = TagDetector(no_bent).detect(c.img, &calib);
      const FrameDetections ds = TagDetector(straight).detect(c.img, &calib);
      ASSERT_EQ(d.status, ds.status) << c.what << ": taking the bow off changed the decision";
      if (d.status == TargetStatus::border_mismatch)
        bowed += d.reason.find("bowed") != std::string::npos;
      // Checked again as a bent print (DetectorSettings::border_max_bent): a card the straight
      // sides' check rejects, kept with the bow taken off.
      if (dflt.status == TargetStatus::detected && d.status != TargetStatus::detected) {
        const double e = max_corner_error(dflt.target()->corners, c.truth);
        ++bent, worst_bent = std::max(worst_bent, e);
        EXPECT_LE(e, 1.0) << c.what << ": kept as a bent print with a corner " << e << " px off";
      }
      // Where the check considers the card as a bent print, its border's inner edge bows as the
      // outer one does (BorderCheck::inner_bow 1, within 3 standard errors).
      const auto quad = TagDetector(with_check(false)).detect(c.img, &calib);
      if (quad.status == TargetStatus::detected) {
        const BorderCheck bc =
            check_border(c.img, quad.target()->corners, tag_pattern("tag36h11", 0), 8, {}, &calib);
        if (!std::isnan(bc.inner_bow)) {
          ++inner_measured;
          worst_inner = std::max(worst_inner, std::abs(bc.inner_bow - 1.0) / bc.inner_bow_se);
          EXPECT_LE(std::abs(bc.inner_bow - 1.0), 3.0 * bc.inner_bow_se)
              << c.what << ": inner edge bows " << bc.inner_bow << " (se " << bc.inner_bow_se
              << ") of the outer edge's bow";
        }
      }
      if (d.status != TargetStatus::detected) continue;
      ASSERT_EQ(dflt.status, TargetStatus::detected) << c.what;
      EXPECT_EQ(max_corner_error(dflt.target()->corners, d.target()->corners), 0.0) << c.what;
      ++kept;
      const double e = max_corner_error(d.target()->corners, c.truth);
      const double es = max_corner_error(ds.target()->corners, c.truth);
      worst = std::max(worst, e);
      worst_straight = std::max(worst_straight, es);
      off_straight += es > 1.0;
      taken_off += max_corner_error(d.target()->corners, ds.target()->corners) > 0.0;
      EXPECT_LE(e, 1.0) << c.what << ": kept with a corner " << e << " px off (" << es
                        << " px where the straight sides meet)";
      // A card kept with one side realigned (realign_and_check()): the check saw another quad.
      if (TagDetector(unrealigned).detect(c.img, &calib).status != TargetStatus::detected) {
        ++realigned;
        continue;
      }
      // The bow of the quad the check saw: the edge-line fit's, before the edge bias is removed.
      const auto unchecked = TagDetector(with_check(false)).detect(c.img, &calib);
      ASSERT_EQ(unchecked.status, TargetStatus::detected) << c.what;
      const QuadBow bow = quad_bow(c.img, unchecked.target()->corners, 8, &calib);
      if (!bow.measured) continue;
      ++measured;
      for (size_t k = 0; k < 4; ++k) {
        const double moved = cv::norm(ds.target()->corners[k] + bow.corner_shift[k] - c.truth[k]);
        worst_moved = std::max(worst_moved, moved);
        EXPECT_LT(moved, 0.35) << c.what << ", corner " << k << ": " << es << " px off, shift "
                               << bow.corner_shift[k];
      }
    }
  std::printf(
      "%d kept (%d with a side realigned; bow measured on %d; moved by it, every corner within "
      "%.2f px of the truth), %d rejected as bowed; the bow taken off %d, every kept corner "
      "within %.2f px (%d kept more than 1 px off with the straight sides' corners, worst %.2f "
      "px); %d more kept as bent prints, every corner within %.2f px; the inner edge's bow "
      "measured on %d, within %.2f standard errors of the outer edge's\n",
      kept, realigned, measured, worst_moved, bowed, taken_off, worst, off_straight, worst_straight,
      bent, worst_bent, inner_measured, worst_inner);
  EXPECT_GE(measured, 10);
  EXPECT_GT(bowed, 0);
  EXPECT_GT(off_straight, 0) << "no card is kept off by more than 1 px without the bow taken "
                                "off: this test shows nothing";
  EXPECT_GT(bent, 0) << "no card the straight sides' check rejects is kept as a bent print";
  EXPECT_GT(inner_measured, 0);
}

// The rotation series' failure made by the renderer (render::PrintModel::border_width): one
// side's black border thinner or thicker than the cells inside it, the grid line along its inner
// edge moved, the outer edge and so the truth's corners where the tag's size puts them (0.05
// and 0.1 cell: 0.6-2 px on the 12-20 px cells of kBentPoses). Without realign_and_check() the
// check rejects such tags as a border thinner or thicker than one cell; with it every tag kept
// has its corners within 1 px of the truth, and a tag is rejected where realigning the side
// would move a corner by more than border_realign_max or, seen far off its normal, where a side
// next to the realigned one has no clean inner edge on the realigned quad.
TEST(BorderCheck, RenderedBorderThinOrThickOnOneSideKeptHalfway) {
  const auto calib = testing::test_calibration();
  const DetectorSettings dflt;
  DetectorSettings off = dflt;
  off.border_realign_max = 0.0;
  const cv::Mat pattern = tag_pattern("tag36h11", 0);
  int pictures = 0, rejected_without = 0, named = 0, kept = 0, kept_realigned = 0, over_cap = 0,
      unmeasured = 0;
  double worst = 0.0;
  for (size_t p = 0; p < kBentPoses.size(); ++p)
    for (size_t side = 0; side < 4; ++side)
      for (const double width : {0.9, 0.95, 1.05, 1.1}) {
        render::PrintModel print;
        print.border_width[side] = width;
        const auto c =
            rendered_case(calib, kBentPoses[p], print, static_cast<unsigned>(60 + p),
                          "rendered, pose " + std::to_string(p) + ", border " +
                              std::to_string(width) + " cell on side " + std::to_string(side));
        ++pictures;
        const auto without = TagDetector(off).detect(c.img, &calib);
        if (without.status == TargetStatus::border_mismatch) {
          ++rejected_without;
          named += without.reason.find(width < 1 ? "thinner" : "thicker") != std::string::npos;
        }
        const auto a = TagDetector(dflt).detect(c.img, &calib);
        if (a.status != TargetStatus::detected) {
          const auto fit = TagDetector(with_check(false)).detect(c.img, &calib);
          ASSERT_EQ(fit.status, TargetStatus::detected) << c.what;
          const auto& q = fit.target()->corners;
          const BorderCheck bc = check_border(c.img, q, pattern, 8, dflt, &calib);
          const auto inner = realign_sides(q, bc, 8, dflt, 1.0, &calib);
          ASSERT_TRUE(inner) << c.what << ": " << a.reason << "; " << describe(bc);
          if (max_corner_error(*inner, q) > dflt.border_realign_max) {
            ++over_cap;
            continue;
          }
          // Otherwise the second check failed because a side measured on the fitted quad has
          // no clean inner edge on the realigned one (held, with the others, to the fixed
          // limit): the only other way this test has seen a tag lost.
          DetectorSettings strict = dflt;
          strict.border_shared_deviation = false;
          const BorderCheck again = check_border(c.img, *inner, pattern, 8, strict, &calib);
          ASSERT_FALSE(again.ok) << c.what;
          bool lost_side = false;
          for (size_t k = 0; k < 4; ++k)
            lost_side = lost_side || (!std::isnan(bc.thickness_error[k]) &&
                                      std::isnan(again.thickness_error[k]));
          EXPECT_TRUE(lost_side) << c.what << ": " << a.reason
                                 << "; realigned: " << describe(again);
          unmeasured += lost_side;
          continue;
        }
        ++kept;
        kept_realigned += without.status != TargetStatus::detected;
        const double e = max_corner_error(a.target()->corners, c.truth);
        worst = std::max(worst, e);
        EXPECT_LT(e, 1.0) << c.what;
      }
  std::printf(
      "%d pictures: %d rejected without the realignment (%d naming the side's border thinner or "
      "thicker), %d kept with it (%d of them realigned), corners within %.2f px; rejected with "
      "it: %d moving a corner by more than border_realign_max, %d with a side unmeasured on the "
      "realigned quad\n",
      pictures, rejected_without, named, kept, kept_realigned, worst, over_cap, unmeasured);
  EXPECT_GE(named, 8) << "the renderer's one-sided border no longer fails the check: the test "
                         "shows nothing";
  EXPECT_GE(kept_realigned, 8);
}

// quad_bow against the truth: on bent cards pictured in linear light (no edge bias, so the
// straight sides fit the inked outline), the corners of the straight sides moved by
// corner_shift lie on the bent print's true corners (measured: within 0.14 px of them where
// the straight sides' corners are up to 1.7 px off, 0.3-0.5 px where they are 4 px off).
TEST(BorderCheck, QuadBowPutsTheCornersWhereTheBentSidesEnd) {
  const auto calib = testing::test_calibration();
  int measured = 0;
  double worst_straight = 0.0;
  for (const double bend : {3.0, -3.0, 5.0, -5.0})
    for (const size_t p : {0u, 1u, 4u}) {
      const auto [what, img, truth] =
          bent_case(calib, p, bend, 1.0, static_cast<unsigned>(800 + p));
      const auto a = TagDetector(with_check(false)).detect(img, &calib);
      if (a.status != TargetStatus::detected) continue;
      const auto& c = a.target()->corners;
      const QuadBow bow = quad_bow(img, c, 8, &calib);
      if (!bow.measured) continue;
      ++measured;
      worst_straight = std::max(worst_straight, max_corner_error(c, truth));
      for (size_t k = 0; k < 4; ++k) {
        // A quadratic extrapolated to the ends, where the bent side's image is a conic: near
        // the decision (a corner 1 px off) within 0.25 px; a 4 px bow's corner within 15 %.
        const double straight = cv::norm(c[k] - truth[k]);
        EXPECT_LT(cv::norm(c[k] + bow.corner_shift[k] - truth[k]), std::max(0.25, 0.15 * straight))
            << what << ", corner " << k << ": straight sides' corner " << straight
            << " px off, bow shift " << bow.corner_shift[k];
      }
    }
  EXPECT_GE(measured, 8);
  EXPECT_GT(worst_straight, 1.0) << "no corner of the straight sides was off: nothing shown";
}

// Flat tags have straight sides, also where blur and JPEG's blocks move the edge samples: over
// cells of 3.8-15 px, blur 0.6-2 px, raw and JPEG at quality 75, every bow measured is below
// 0.3 px, far from border_max_bow. Where the border is too thin for its blur (the inner edge
// within 3 sigma of the window across the outer edge), the data cells next to the border would
// move the samples (0.7-1.1 px of apparent bow on 3.8-5 px cells blurred by 1.5-2 px) and the
// bow is not measured.
TEST(BorderCheck, FlatTagsShowNoBow) {
  const auto calib = testing::test_calibration();
  int measured = 0;
  double worst = 0.0;
  for (const double dist : {1.0, 2.0, 4.0})
    for (const double blur : {0.6, 1.5, 2.0})
      for (const int quality : {0, 75})
        for (int p = 0; p < 3; ++p) {
          char what[120];
          std::snprintf(what, sizeof what, "distance %.0f m, blur %.1f px, JPEG %d, pose %d", dist,
                        blur, quality, p);
          const obs::SE3 pose =
              testing::facing_pose(dist, 0.05 * p - 0.1, 0.03 * p - 0.05,
                                   {0.3 * std::sin(p), 0.4 * std::cos(p), 0.5 * p});
          testing::SynthSettings opt;
          opt.black = 12.0;
          opt.noise_sigma = 2.0;
          opt.seed = static_cast<unsigned>(900 + p);
          cv::Mat img = testing::render_camera_picture(calib, {{0, kSize, pose, {}}}, opt, blur);
          if (quality > 0) {
            std::vector<uchar> jpeg;
            cv::imencode(".jpg", img, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality});
            img = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
          }
          const auto a = TagDetector(with_check(false)).detect(img, &calib);
          if (a.status != TargetStatus::detected) continue;
          const BorderCheck bc = check_border(img, a.target()->corners, tag_pattern("tag36h11", 0),
                                              8, DetectorSettings{}, &calib);
          EXPECT_EQ(bc.reason.find("bowed"), std::string::npos) << what << ": " << bc.reason;
          const QuadBow bow = quad_bow(img, a.target()->corners, 8, &calib);
          if (!bow.measured) continue;
          ++measured;
          for (size_t k = 0; k < 4; ++k) {
            worst = std::max(worst, cv::norm(bow.corner_shift[k]));
            EXPECT_LT(cv::norm(bow.corner_shift[k]), 0.3) << what << ", corner " << k;
          }
        }
  std::printf("bow measured on %d flat tags, the largest %.2f px\n", measured, worst);
  EXPECT_GE(measured, 20);
}

// A camera's sharpening (an unsharp mask, as phones and webcams apply before JPEG) on flat tags
// with small cells: the blur estimate reads the steepened edges as unblurred, so the bow is
// measured where the data cells next to the border, white at some and black at others, move
// the outer edge's samples through the mask's negative lobe, and flat sides look bowed (the
// 12-14 px tags of swatbotics_clipboard/clipboard08.png, cells of 1.5-1.8 px: 0.74-0.82 px).
// Measured over masks of amount 1-3 and radius 0.8-1.5 px, blur 0.4-1 px, raw and JPEG 85
// (2026-12-04): the largest bow 0.90 px on cells under 2 px, 0.67 on 2-2.5 px, 0.56 on
// 2.5-3 px, 0.48 on 3-6 px; rendered flat tags in sRGB 0.5-0.70 px on cells of 2.5-2.6 px. So
// the bow is taken off only on cells of at least border_bow_min_cell (4 px), where a flat
// tag's stays under border_bow_correction; and no flat tag here has its corners moved.
TEST(BorderCheck, SharpenedSmallCellsLookBowed) {
  const auto calib = testing::test_calibration();
  DetectorSettings unchecked = with_check(false);
  unchecked.quad_decimate = 1.0;  // tags down to 15 px
  DetectorSettings dflt, straight;
  dflt.quad_decimate = straight.quad_decimate = 1.0;
  straight.border_bow_correction = 0.0;
  int measured_small = 0, measured_large = 0, false_bows_small = 0, kept = 0, moved = 0;
  double worst_small = 0.0, worst_large = 0.0;
  for (const double dist : {3.0, 5.0, 6.0, 7.0, 8.0})
    for (const int quality : {0, 85})
      for (int p = 0; p < 8; ++p) {
        const obs::SE3 pose =
            testing::facing_pose(dist, 0.03 * p - 0.1, 0.02 * p - 0.05,
                                 {0.35 * std::sin(1.3 * p), 0.5 * std::cos(0.7 * p), 0.4 * p});
        testing::SynthSettings opt;
        opt.black = 12.0;
        opt.noise_sigma = 2.0;
        opt.seed = static_cast<unsigned>(2900 + p + 10 * quality);
        cv::Mat img = testing::render_camera_picture(calib, {{0, kSize, pose, {}}}, opt, 0.7);
        cv::Mat f, g;
        img.convertTo(f, CV_32F);
        cv::GaussianBlur(f, g, cv::Size(0, 0), 1.5);
        f = f * 3.0 - g * 2.0;  // unsharp mask, amount 2
        f.convertTo(img, CV_8U);
        if (quality > 0) {
          std::vector<uchar> jpeg;
          cv::imencode(".jpg", img, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality});
          img = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
        }
        char what[100];
        std::snprintf(what, sizeof what, "distance %.0f m, JPEG %d, pose %d", dist, quality, p);
        const auto a = TagDetector(unchecked).detect(img, &calib);
        if (a.status != TargetStatus::detected) continue;
        const auto& c = a.target()->corners;
        const double side = narrowest_side(c);
        const QuadBow bow = quad_bow(img, c, 8, &calib);
        if (bow.measured) {
          double shift = 0.0;
          for (size_t k = 0; k < 4; ++k) shift = std::max(shift, cv::norm(bow.corner_shift[k]));
          const bool small = side / 8.0 < DetectorSettings{}.border_bow_min_cell;
          (small ? measured_small : measured_large) += 1;
          double& worst = small ? worst_small : worst_large;
          worst = std::max(worst, shift);
          false_bows_small += small && shift > DetectorSettings{}.border_bow_correction;
          if (!small) {
            EXPECT_LE(shift, DetectorSettings{}.border_bow_correction)
                << what << ": a flat tag with cells of " << side / 8.0 << " px bowed";
          }
        }
        const auto d = TagDetector(dflt).detect(img, &calib);
        const auto ds = TagDetector(straight).detect(img, &calib);
        ASSERT_EQ(d.status, ds.status) << what;
        if (d.status != TargetStatus::detected) continue;
        ++kept;
        const double move = max_corner_error(d.target()->corners, ds.target()->corners);
        moved += move > 0.0;
        EXPECT_EQ(move, 0.0) << what << ": a flat tag's corners moved by its bow";
      }
  std::printf(
      "bow measured on %d flat sharpened tags with cells under 4 px (largest %.2f px, %d above "
      "border_bow_correction) and %d with larger cells (largest %.2f px); %d kept, %d of them "
      "moved\n",
      measured_small, worst_small, false_bows_small, measured_large, worst_large, kept, moved);
  EXPECT_GT(false_bows_small, 0) << "no small sharpened tag looks bowed: this test shows nothing";
  EXPECT_GE(measured_large, 10);
}

// The bow's settings out of their range: one message naming the field.
TEST(BorderCheck, BowSettingsOutOfRangeNamed) {
  const auto message = [](const DetectorSettings& s) {
    try {
      validate(s);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  DetectorSettings s;
  EXPECT_EQ(message(s), "");
  s.border_bow_correction = -0.1;
  EXPECT_NE(message(s).find("border_bow_correction"), std::string::npos) << message(s);
  s = DetectorSettings{};
  s.border_bow_min_cell = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(s).find("border_bow_min_cell"), std::string::npos) << message(s);
  s = DetectorSettings{};
  s.border_max_bent = 101.0;
  EXPECT_NE(message(s).find("border_max_bent"), std::string::npos) << message(s);
}

}  // namespace
}  // namespace netvmo
