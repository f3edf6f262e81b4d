// Test utility (not part of the library): synthesizes camera images of AprilTags at known poses
// by exact supersampled inverse mapping, and small dataset folders around them. Reusable by
// later acceptance tests: link the `netvmo_test_synth` library and include "synth.hpp".
//
// Image model: each output pixel (col,row) covers [col-0.5, col+0.5] x [row-0.5, row+0.5]
// (OpenCV convention). Each of supersample^2 sub-samples is back-projected (through the
// distortion model with cv::undistortPoints iterated to convergence when the calibration has
// distortion), its ray is intersected with every tag plane facing the camera, and the nearest
// hit looks up the tag bitmap (libapriltag's apriltag_to_image, row 0 = top of the printed tag =
// +y) surrounded by an extra white quiet zone; rays that miss show the background level.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::testing {

struct SynthTag {
  int id = 0;
  double size = 0.2;                               ///< black border side, metres
  obs::SE3 g_io = obs::SE3::Identity();            ///< tag -> camera
  std::vector<std::pair<int, int>> flipped_cells;  ///< (row, col) bitmap cells to invert
  /// Curvature of the card [1/m]: the print wrapped, without stretching, on a cylinder whose
  /// axis is parallel to the tag's y axis, so its x axis (and the sides along it) bends and its
  /// y axis stays straight; > 0 bulges toward the face (the ends curl away from the camera),
  /// < 0 the other way; 0: flat. A point at arc length u along x lies at
  /// (sin(k u) / k, y, -(1 - cos(k u)) / k) in the tag frame.
  double bend = 0.0;
};

struct SynthSettings {
  std::string family = "tag36h11";
  int supersample = 4;        ///< sub-samples per pixel side
  double background = 128.0;  ///< gray level where no tag is hit
  double black = 20.0, white = 230.0;
  double quiet_zone_cells = 1.0;  ///< white margin added around the bitmap (cells)
  double noise_sigma = 0.0;       ///< Gaussian noise (gray levels), seeded
  std::uint64_t seed = 1;
  std::vector<cv::Rect> occluders;  ///< image rectangles painted with `occluder_level`
  double occluder_level = 90.0;
  /// Ink spread of the print [cells]: the black grows by this much on every edge (negative:
  /// shrinks), its corners rounded (a Euclidean dilation of the black cells); |value| < 0.5.
  double ink_spread = 0.0;
  /// Width of the printed black border ring [cells], its outer edge where the bitmap puts it:
  /// a print whose border is thinner (< 1) or thicker (> 1) than its data cells on every side,
  /// the data cells left in place (1: as the bitmap; a border wider than 1 covers the data
  /// cells next to it).
  double border_width = 1.0;
  /// Width of the printed black border per edge of the bitmap [cells]: its top (row 0, the
  /// tag's +y), right (+x), bottom and left edges, multiplying border_width there: a print whose
  /// border is thinner or thicker on one side only (a trimmed or misregistered print), its outer
  /// edge and the data cells where the bitmap puts them.
  std::array<double, 4> border_width_per_edge{1.0, 1.0, 1.0, 1.0};
  /// render_camera_picture: motion over the exposure [px], the image displacement of the scene
  /// during the exposure (a line kernel in linear light, before the tone curve); 0: none.
  cv::Point2d motion_blur{0.0, 0.0};
};

/// 8-bit gray image of the tags seen by a camera.
cv::Mat render_tags(const io::Calibration& calib, const std::vector<SynthTag>& tags,
                    const SynthSettings& opt = {});

/// A camera's picture of the tags: render_tags() without noise, taken as linear light, blurred
/// by a Gaussian of `blur_sigma` px (0: none), encoded as v^(1/gamma) (2.2 about as sRGB; 1:
/// linear), then Gaussian noise of opt.noise_sigma (seeded with opt.seed) and 8-bit rounding.
cv::Mat render_camera_picture(const io::Calibration& calib, const std::vector<SynthTag>& tags,
                              const SynthSettings& opt, double blur_sigma, double gamma = 2.2);

/// The true corners of a tag (obs::FeatureModel::square order) in OpenCV pixels, with
/// distortion (cv::projectPoints).
std::array<cv::Point2d, 4> project_corners(const io::Calibration& calib, const obs::SE3& g_io,
                                           double size);

/// The true corners of a tag as synthesized (bent as tag.bend says; tag.size the black
/// square's side measured along the print).
std::array<cv::Point2d, 4> project_corners(const io::Calibration& calib, const SynthTag& tag);

/// Largest distance between corresponding corners of two quads [px].
double max_corner_error(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b);

/// The quad with side k (corner k to corner k+1) moved by `d` px along its outward normal
/// (away from the quad's centre; negative: inwards), both its corners alike.
std::array<cv::Point2d, 4> move_side(const std::array<cv::Point2d, 4>& quad, size_t k, double d);

/// A 640x480 calibration (fx 610, fy 605, cx 321.7, cy 238.4), optionally with moderate
/// distortion (k1 -0.12, k2 0.05, p1 4e-4, p2 -3e-4, k3 0).
io::Calibration test_calibration(bool distortion = false);

/// g_io for a tag at `distance` along the optical axis offset by (dx, dy) metres, facing the
/// camera (tag z toward -z_camera) and then tilted by the rotation vector `tilt` (tag frame).
obs::SE3 facing_pose(double distance, double dx = 0.0, double dy = 0.0,
                     const obs::Vec3& tilt = obs::Vec3::Zero());

/// RMS of corner differences (pixels).
double corner_rms(const std::array<cv::Point2d, 4>& a, const std::array<cv::Point2d, 4>& b);

/// One camera of a synthetic dataset: its id, calibration and per-frame tag pose g_io.
struct SynthCamera {
  int id = 1;
  io::Calibration calib;
  obs::SE3 g_wi = obs::SE3::Identity();
};

struct SynthDatasetSpec {
  std::vector<SynthCamera> cameras;
  std::vector<obs::SE3> g_wo;  ///< target pose per frame
  int target_id = 0;
  double tag_size = 0.2;
  double fps = 30.0;
  bool video = false;  ///< write cam_<id><video_ext> instead of cam_<id>/%06d.png
  std::string video_ext = ".avi";
  std::string video_fourcc = "MJPG";  ///< e.g. MJPG (.avi), FFV1 (.avi, lossless), mp4v (.mp4)
  SynthSettings options;
};

/// `cameras` cameras 0.3 m apart along world x (identity orientation, ids 1..n, the test
/// calibration) and a target 2 m in front moving sideways and turning over `frames` frames.
SynthDatasetSpec simple_dataset_spec(int cameras, int frames, bool video = false);

/// Writes network.yaml (edges: a path 1-2-...), calib/cam_<id>.yaml, frames, truth.csv and
/// target.csv into `dir` (created). Returns the true corners [camera][frame] (tag in front).
std::vector<std::vector<std::array<cv::Point2d, 4>>> write_synth_dataset(
    const std::filesystem::path& dir, const SynthDatasetSpec& spec);

/// A fresh empty temporary directory for a test (removed first if it exists).
std::filesystem::path fresh_dir(const std::string& name);

/// `raw`, an image of camera `calib` (with lens distortion), rectified as an image pipeline does
/// it: to the pinhole camera of the same focal lengths magnified by `m` (principal point scaled
/// with the pixel centres), its image `m` times as large, each pixel taken from `raw` by
/// cv::initUndistortRectifyMap and cv::remap with `interpolation` (cv::INTER_NEAREST,
/// cv::INTER_LINEAR, ...).
struct Rectified {
  io::Calibration calib;
  cv::Mat image;
};
Rectified rectify(const cv::Mat& raw, const io::Calibration& calib, double m, int interpolation);

}  // namespace netvmo::testing
