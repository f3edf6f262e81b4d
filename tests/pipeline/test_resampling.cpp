// Images resampled by nearest neighbour told apart (frontend/resampling.hpp): the closed form of
// an image enlarged twice by copying pixels; a tag pictured through lens distortion and JPEG as
// a camera gives it, and the same rectified bilinearly, not flagged, rectified by nearest
// neighbour at magnifications 1.3 and 1.65 flagged; the real photos in this repository (none of
// them resampled) not flagged; and the per-camera step measuring each camera's first image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/run/camera_step.hpp"
#include "synth.hpp"

namespace netvmo {
namespace {
namespace fs = std::filesystem;
using namespace frontend;

cv::Mat noise_image(int rows, int cols, unsigned seed) {
  cv::Mat img(rows, cols, CV_8UC1);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> level(0, 255);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) img.at<uchar>(r, c) = static_cast<uchar>(level(rng));
  return img;
}

// Enlarged twice by copying each pixel into a 2 x 2 block, every pair of neighbouring pixels on a
// steep edge is a copy: a pair straddling two blocks has a copy of its first pixel before it, so
// no step there. Hence exactly 1. The noise image itself is not flagged.
TEST(Resampling, TwiceEnlargedByCopyingRepeatsEveryPairOnASteepEdge) {
  const cv::Mat src = noise_image(64, 80, 7);
  cv::Mat big;
  cv::resize(src, big, cv::Size(), 2.0, 2.0, cv::INTER_NEAREST);
  const Resampling r = measure_resampling(big);
  EXPECT_GT(r.pairs, 1000);
  EXPECT_DOUBLE_EQ(r.repeated, 1.0);
  EXPECT_TRUE(r.nearest_neighbour);
  const Resampling own = measure_resampling(src);
  std::printf("noise image: %.3f of %ld pairs repeated\n", own.repeated, own.pairs);
  EXPECT_GT(own.pairs, 1000);
  EXPECT_FALSE(own.nearest_neighbour);
  // Without a steep edge nothing is decided.
  const Resampling flat = measure_resampling(cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
  EXPECT_EQ(flat.pairs, 0);
  EXPECT_FALSE(flat.nearest_neighbour);
  EXPECT_FALSE(resampling_warning(1, flat));
}

// A tag pictured through lens distortion (k1 -0.3), blurred, with the tone curve, noise and JPEG
// at quality 80; then rectified (testing::rectify) by nearest neighbour and bilinearly.
TEST(Resampling, NearestNeighbourRectifiedFlaggedCameraImageAndBilinearNot) {
  io::Calibration raw = testing::test_calibration();
  raw.dist = {-0.3, 0.05, 4e-4, -3e-4, 0.0};
  testing::SynthSettings opt;
  opt.black = 12.0;
  opt.noise_sigma = 2.0;
  opt.seed = 11;
  const obs::SE3 pose = testing::facing_pose(1.4, 0.35, 0.2, {0.2, -0.1, 0.5});
  cv::Mat picture = testing::render_camera_picture(raw, {{0, 0.2, pose, {}}}, opt, 0.6);
  std::vector<uchar> jpeg;
  cv::imencode(".jpg", picture, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  picture = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
  const Resampling own = measure_resampling(picture);
  std::printf("camera image: %.3f of %ld pairs repeated\n", own.repeated, own.pairs);
  EXPECT_GT(own.pairs, ResamplingSettings().min_pairs);
  EXPECT_FALSE(own.nearest_neighbour);
  for (const double m : {1.3, 1.65}) {
    const auto nearest = testing::rectify(picture, raw, m, cv::INTER_NEAREST);
    const auto bilinear = testing::rectify(picture, raw, m, cv::INTER_LINEAR);
    const Resampling rn = measure_resampling(nearest.image);
    const Resampling rb = measure_resampling(bilinear.image);
    std::printf("magnification %.2f: nearest %.3f of %ld, bilinear %.3f of %ld pairs repeated\n", m,
                rn.repeated, rn.pairs, rb.repeated, rb.pairs);
    EXPECT_TRUE(rn.nearest_neighbour) << "magnification " << m;
    EXPECT_FALSE(rb.nearest_neighbour) << "magnification " << m;
    EXPECT_GT(rb.pairs, ResamplingSettings().min_pairs);
  }
}

// The 29 real photos of datasets/real_photos/photos, none of them resampled (MANIFEST.md).
TEST(Resampling, RealPhotosInTheRepositoryNotFlagged) {
  int photos = 0;
  double most = 0.0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(NETVMO_SOURCE_DIR) /
                                                        "datasets/real_photos/photos")) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg") continue;
    const cv::Mat gray = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(gray.empty()) << e.path();
    const Resampling r = measure_resampling(gray);
    ++photos;
    most = std::max(most, r.repeated);
    EXPECT_GT(r.pairs, ResamplingSettings().min_pairs) << e.path();
    EXPECT_FALSE(r.nearest_neighbour) << e.path() << ": " << r.repeated << " of " << r.pairs;
  }
  std::printf("%d photos, at most %.3f of the pairs on steep edges repeated\n", photos, most);
  EXPECT_EQ(photos, 29);
}

// The per-camera step measures a camera's first image read (not an unreadable one), once, and
// the warning names the camera.
TEST(Resampling, ThePerCameraStepMeasuresTheFirstImage) {
  cv::Mat big;  // 640x480, the calibration's size
  cv::resize(noise_image(240, 320, 3), big, cv::Size(), 2.0, 2.0, cv::INTER_NEAREST);
  const io::Calibration calib = testing::test_calibration();
  std::vector<io::TargetConfig> targets(1);
  targets[0].size = 0.2;
  DetectorSettings settings;
  set_targets(settings, targets);
  FrontEnd fe(settings);
  TrackState track;
  cv::Mat image;
  std::vector<Observation> out;
  // An unreadable first image is not measured: the first image read is.
  EXPECT_TRUE(run::observe_camera([]() -> cv::Mat { throw InputError("unreadable"); }, calib, fe,
                                  track, targets, true, image, out));
  EXPECT_FALSE(track.resampling.has_value());
  ASSERT_FALSE(run::observe_camera([&] { return big.clone(); }, calib, fe, track, targets, false,
                                   image, out));
  ASSERT_TRUE(track.resampling.has_value());
  EXPECT_TRUE(track.resampling->nearest_neighbour);
  const auto w = resampling_warning(7, *track.resampling);
  ASSERT_TRUE(w.has_value());
  EXPECT_NE(w->find("camera 7: its images look resampled by nearest neighbour"), std::string::npos)
      << *w;
  // The next image is not measured again.
  const cv::Mat own = noise_image(480, 640, 4);
  ASSERT_FALSE(run::observe_camera([&] { return own.clone(); }, calib, fe, track, targets, false,
                                   image, out));
  EXPECT_TRUE(track.resampling->nearest_neighbour);
}

}  // namespace
}  // namespace netvmo
