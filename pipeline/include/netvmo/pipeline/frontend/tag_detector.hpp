// AprilTag detection (libapriltag) with OpenCV corner refinement and the target decision.
//
// Pixel convention: all corners are in OpenCV pixel coordinates (pixel (col,row) centred at
// continuous (col,row)). libapriltag 3.3 reports corners with pixel centres at +0.5, i.e.
//   u_opencv = u_apriltag - 0.5,  v_opencv = v_apriltag - 0.5
// (measured on synthesized images with exactly known corners, see tests/pipeline).
//
// Corner order: libapriltag's, unchanged. For a tag of side s in the object frame (x right of
// the printed tag, y up, z out of the printed face) corner k is the image of
//   c0 = (-s/2,-s/2,0), c1 = (s/2,-s/2,0), c2 = (s/2,s/2,0), c3 = (-s/2,s/2,0)
// i.e. obs::FeatureModel::square(s).points_o[k] (verified index by index in the tests).
#pragma once

#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// Sub-pixel corner refinement applied (in OpenCV) to the target's corners after detection.
enum class Refinement {
  none,           ///< libapriltag's corners as they are (its refine_edges already fits edges)
  corner_subpix,  ///< cv::cornerSubPix, window scaled to the tag's cell size
  edge_lines,     ///< lines fitted to sub-pixel samples of the four outer border edges,
                  ///< intersected (in undistorted coordinates when a calibration is given)
};
const char* to_string(Refinement r);
/// "none", "subpix", "edges"; throws InputError otherwise.
Refinement parse_refinement(const std::string& name);

/// Detector settings. Defaults documented next to each field.
struct DetectorSettings {
  // libapriltag (apriltag_detector_t) settings
  std::string family = "tag36h11";  ///< tag family (see render::tag_families())
  double quad_decimate = 2.0;       ///< decimation of the image for quad search (>= 1)
  double quad_sigma = 0.0;          ///< Gaussian blur sigma applied before quad search
  int nthreads = 2;                 ///< worker threads of libapriltag
  bool refine_edges = true;         ///< libapriltag's edge refinement of the quads
  double decode_sharpening = 0.25;  ///< sharpening of the decoded bit samples
  int bits_corrected = 2;           ///< error bits the decoder may correct (libapriltag default)
  /// libapriltag qtp.min_white_black_diff: local contrast (gray levels) below which a region is
  /// not thresholded. libapriltag's default is 5; 20 skips the quad fitting of sensor-noise
  /// clusters (about 5x faster on 640x480 frames with noise sigma 2, see the README's front-end
  /// benchmark) and still finds tags whose black/white contrast is 40 gray levels or more (tested).
  int min_white_black_diff = 20;
  // Acceptance of the target tag
  int target_id = 0;                  ///< the target's tag id
  double min_decision_margin = 20.0;  ///< reject target detections with a lower decision margin
  int max_hamming = 1;                ///< reject target detections with more corrected bits
  // Refinement of the accepted target's corners
  Refinement refinement = Refinement::edge_lines;
};

/// One decoded tag.
struct TagDetection {
  int id = -1;
  int hamming = 0;
  double margin = 0.0;                   ///< libapriltag's decision margin
  std::array<cv::Point2d, 4> corners{};  ///< OpenCV pixels, libapriltag order
  cv::Point2d center;                    ///< OpenCV pixels
};

enum class TargetStatus { detected, not_found, duplicate_id, low_margin, high_hamming };
const char* to_string(TargetStatus s);

/// All tags decoded in a frame and the decision about the target.
struct FrameDetections {
  std::vector<TagDetection> all;  ///< every decoded tag (other ids are reported, not used)
  TargetStatus status = TargetStatus::not_found;
  int target_index = -1;  ///< index into `all` of the accepted target, or -1
  /// The accepted target detection (refined corners), or nullptr.
  const TagDetection* target() const {
    return target_index >= 0 ? &all[static_cast<size_t>(target_index)] : nullptr;
  }
};

/// libapriltag detector, created once and reused across frames (not thread-safe: one
/// detect() at a time; it uses `nthreads` workers internally).
class TagDetector {
 public:
  explicit TagDetector(DetectorSettings settings = {});
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;
  TagDetector(TagDetector&&) noexcept;
  TagDetector& operator=(TagDetector&&) noexcept;

  /// Detects all tags in an 8-bit gray (or BGR, converted) image, decides about the target and
  /// refines the accepted target's corners. `calib` (optional) lets the edge-line refinement
  /// fit straight lines in undistorted coordinates.
  FrameDetections detect(const cv::Mat& image, const io::Calibration* calib = nullptr);
  /// The same, searching only `region` of the image (tags must lie wholly inside it); corners
  /// are reported and refined in whole-image pixels.
  FrameDetections detect(const cv::Mat& image, const cv::Rect& region,
                         const io::Calibration* calib = nullptr);

  const DetectorSettings& settings() const;
  /// Cells across the black border square (8 for tag36h11): corners are at this square.
  int border_cells() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Refines the four corners of one detected quad in place (OpenCV). `border_cells` is the
/// number of bit cells across the black border square. Exposed for tests and benchmarks.
void refine_corners(const cv::Mat& gray, std::array<cv::Point2d, 4>& corners, Refinement mode,
                    int border_cells, const io::Calibration* calib = nullptr);

}  // namespace netvmo::frontend
