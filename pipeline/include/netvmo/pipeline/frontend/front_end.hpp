// The tag front end: detection + refinement + undistortion into what the observer consumes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/frontend/resampling.hpp"
#include "netvmo/pipeline/frontend/tag_detector.hpp"
#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"

namespace netvmo::frontend {

/// One camera's observation of one target in one frame: the front end's output (the stage after
/// the detector's FrameDetections, before the observer's obs::Measurement). A target with a
/// bundle (several tags on one body) is observed by every tag of it that is accepted, in slot
/// order (0 the primary, k >= 1 network.yaml's target.bundle[k - 1]); the first accepted tag's
/// fields are also those of the single-tag members (tag_id, hamming, margin, corners_px). The
/// per-camera step (run/camera_step.hpp) adds the PnP pose.
struct Observation {
  bool delta = false;  ///< delta_i(t): at least one tag of the target decoded and accepted
  TargetStatus status = TargetStatus::not_found;
  std::string reason;  ///< why the target was rejected (empty when detected)
  int tag_id = -1;     ///< the first accepted tag's id when detected, else -1
  int hamming = 0;
  double margin = 0.0;                      ///< decision margin of the first accepted tag
  std::array<cv::Point2d, 4> corners_px{};  ///< its refined corners, OpenCV pixels
  /// Slots of the accepted tags, increasing (a single tag: {0} when detected).
  std::vector<int> slots;
  /// Refined corners of every accepted tag, as `slots` (OpenCV pixels, libapriltag order).
  std::vector<std::array<cv::Point2d, 4>> tag_corners_px;
  /// Undistorted normalized coordinates [x0,y0,...,x3,y3] of every accepted tag in `slots`
  /// order (8 per tag), corner k of a tag matching tag_points()'s order. Eight zeros when not
  /// detected.
  Eigen::VectorXd f_normalized = Eigen::VectorXd::Zero(8);
  /// The covariance of each accepted tag's 8 entries of f_normalized, in `slots` order: the edge
  /// fits' corner covariance (TagDetection::corner_covariance) or, without one,
  /// DetectorSettings::corner_sigma_px squared on the diagonal, taken to normalized coordinates
  /// by the inverse of K's upper 2x2 (first order; lens distortion's own Jacobian is left out,
  /// which at the corners of a typical lens changes it by a few per cent). Tags are independent.
  std::vector<CornerCovariance> f_covariance;

  // Set by the per-camera step (run::observe_camera), not by FrontEnd:
  std::optional<obs::SE3> g_io_pnp;  ///< the PnP pose of the target in the camera when detected
  /// g_io_pnp's first-order covariance from the corners' (pnp_covariance: the tag's position and
  /// rotation in the camera frame, ROS's PoseWithCovariance order).
  std::optional<PoseCovariance> pnp_covariance;
  /// The object points of f_normalized when the target has a bundle (tag_points of the accepted
  /// tags; empty for a single tag, whose points are the error model's fixed square).
  std::vector<obs::Vec3> points_o;
  bool read_failed = false;  ///< the image could not be read (only with keep_going)
};

/// Corners (OpenCV pixels) to the observer's feature vector f (undistorted normalized).
Eigen::Matrix<double, 8, 1> normalized_features(const std::array<cv::Point2d, 4>& corners_px,
                                                const io::Calibration& calib);

/// A detection's corner covariance in normalized coordinates (Observation::f_covariance).
CornerCovariance normalized_covariance(const TagDetection& t, const io::Calibration& calib,
                                       const DetectorSettings& s);

/// The covariance of an observation's whole f_normalized: its tags' f_covariance blocks on the
/// diagonal; nullopt when it has not one per tag (an observation read back from a file).
std::optional<Eigen::MatrixXd> f_covariance_matrix(const Observation& obs);

/// The detector settings' tag ids for a target: family, primary id and bundle ids.
void set_target(DetectorSettings& s, const io::TargetConfig& target);
/// The same for several targets decided in one pass (DetectorSettings::tags_per_target; one
/// target: as set_target). The targets share the first one's family.
void set_targets(DetectorSettings& s, const std::vector<io::TargetConfig>& targets);

/// The object points (object frame o) that go with an observation's f_normalized: for each
/// accepted slot k, the 4 corners of that tag, g_ot(k) * (+-s_k/2, +-s_k/2, 0) in libapriltag's
/// order. For a single tag this is obs::FeatureModel::square(size).
obs::FeatureModel tag_points(const io::TargetConfig& target, const std::vector<int>& slots);
/// The object points of a detected observation's f_normalized: the primary tag's square for a
/// single-tag target, else tag_points(target, o.slots).
obs::FeatureModel observation_model(const io::TargetConfig& target, const Observation& o);

/// Tracking and acquisition: how each frame is searched (FrontEnd::observe with a TrackState).
/// With several targets "the target" below is every target: the window covers every tag
/// accepted in the last frame, and the whole image is searched whenever the window misses any
/// target (so a target out of a camera's view costs that camera a full-frame search per frame,
/// which a camera that sees no target at all skips while its image is unchanged, see
/// change_pixels); the acquisition pass runs only while no target is seen.
///  - While a camera keeps detecting the target, the next frame is searched first in a window
///    around the last corners, at full resolution (decimate 1) when the last tag's narrowest
///    side was below `full_res_below_px`, else decimated in proportion to that side up to
///    `window_max_decimate` (window_decimate()); if that fails and `shadow_retry`, the window again
///    on a locally normalised copy (normalize_illumination(), for a hard shadow edge across the
///    tag). Only when those fail (or every `full_frame_every` frames, then after the full frame)
///    is the whole image searched at the settings' decimation.
///  - Acquisition: while the camera has no target (no detection in the previous frame), every
///    `acquire_every`-th such frame (the first one included) that the decimated search misses is
///    searched again at full resolution: small tags (~15-30 px) that decimate 2 misses are
///    found within `acquire_every` frames, at the cost of one full-resolution search per
///    `acquire_every` blind frames.
/// delta still comes from a real decode in this frame. A duplicate_id result ends the frame's
/// searches. Caveat: while tracking, a second tag with the target's id outside the window is
/// not seen, so the duplicate-id rejection is checked on full-frame searches only.
struct TrackingSettings {
  bool enabled = true;
  double window_margin = 0.75;  ///< window = corner bounding box grown by this x its size ...
  int window_pad = 24;          ///< ... plus this many pixels on every side
  int full_frame_every = 30;    ///< a full-frame search at least this often (frames)
  /// Window searched at decimate 1 when the last tag's narrowest side is below this [px]
  /// (0: never). 40 px covers the sizes decimate 2 misses (docs/frontend.md, "Small tags: recall
  /// against tag size").
  double full_res_below_px = 40.0;
  /// Above full_res_below_px the window is decimated as far as keeps the last tag's narrowest
  /// side as many decimated pixels as a side of full_res_below_px keeps at the detector's
  /// decimation (20 at the defaults), up to this (window_decimate()); set to the detector's
  /// decimation or less, the window is never decimated more than the whole image. The window
  /// grows with the tag, so its search then costs about the same whatever the tag's size
  /// (docs/frontend.md, "The window's decimation").
  int window_max_decimate = 4;
  /// Full-resolution acquisition pass every this many blind frames (0: never). 10 adds one
  /// full-resolution search per 10 frames of a camera that sees nothing (docs/frontend.md, "Small
  /// tags: recall against tag size", ms/frame).
  int acquire_every = 10;
  /// A second window search on a locally normalised copy when the window search fails.
  bool shadow_retry = true;
  /// A camera without its target skips the whole-image search while its image is still the one
  /// of its last whole-image search (which found no target): fewer than change_pixels pixels
  /// lie more than change_dn gray levels outside the range of that image's 3x3 neighbourhood
  /// around them (ChangeReference). That search's result stands for the
  /// frame. It searches anyway at least every full_frame_every frames; the acquisition pass,
  /// when due, is skipped alike while the image is the one of the last acquisition pass, for
  /// at most full_frame_every blind frames after that pass. A tag that comes
  /// into view changes far more pixels than that (its black border against anything lighter),
  /// while sensor and JPEG noise stay far below 24 levels (docs/frontend.md, "Cameras that see
  /// nothing"). change_pixels = 0: never skip.
  int change_dn = 24;
  int change_pixels = 16;
};
/// Checks a TrackingSettings; throws InputError naming the field.
void validate(const TrackingSettings& t);

/// The decimation of the tracking window's search when the last tag's narrowest side is `side`
/// px and the detector's decimation `quad_decimate`: 1 below t.full_res_below_px; else the whole
/// number floor(quad_decimate x side / full_res_below_px), at least quad_decimate and at most
/// t.window_max_decimate (quad_decimate where that is below it or full_res_below_px is 0).
double window_decimate(double side, double quad_decimate, const TrackingSettings& t);

/// An image kept to tell whether a later one is still the same scene: each pixel's 3x3
/// neighbourhood's least and greatest value, so that a shift of the image by up to a pixel (a
/// camera's vibration, the renderer's sample positions) is no change (FrontEnd::unchanged).
struct ChangeReference {
  cv::Mat low, high;
  bool empty() const { return low.empty(); }
};

/// One camera's tracking state (keep one per camera, pass it on every frame).
struct TrackState {
  /// Corners of every tag accepted in the last frame (every tag of a bundle, of every target):
  /// the window covers them all. Empty: the camera had no target in the last frame.
  std::vector<std::array<cv::Point2d, 4>> last_all;
  /// When no tag was accepted in the last frame: the corners of the targets' tags it decoded
  /// that the frame check rejected (border_mismatch). The tag is there (a side of it failed the
  /// check, or it is leaving the image), so the next frame searches the window around it first,
  /// as while tracking, before the whole image; it counts as a frame without the target.
  std::vector<std::array<cv::Point2d, 4>> last_seen;
  int frames_since_full = 0;
  int blind_frames = 0;  ///< consecutive frames without the target (acquisition period)
  /// The image of the last whole-image search that found no target, and that search's result
  /// (TrackingSettings::change_pixels); empty once the target is found.
  ChangeReference whole_image;
  FrameDetections whole_result;
  /// The image of the last acquisition pass that found no target (empty: none since), and
  /// blind_frames at that pass.
  ChangeReference acquisition_image;
  int acquisition_at = 0;
  /// How the last frame was searched, for tests and benchmarks: bit 0 window, bit 1 normalised
  /// window, bit 2 full frame, bit 3 full-resolution acquisition; bit 4: the full frame's search
  /// was skipped (its image unchanged), bit 5: the acquisition pass was.
  unsigned searches = 0;
  /// The search that found the target in the last frame (one bit as above), 0 when none.
  unsigned found_by = 0;
  /// The decimation the last frame's window was searched at (window_decimate()), 0 when its
  /// window was not searched.
  double window_decimate = 0.0;
  /// The camera's first image read, measured for nearest-neighbour resampling by the per-camera
  /// step (run/camera_step.hpp); empty until then.
  std::optional<Resampling> resampling;
};
inline constexpr unsigned kSearchWindow = 1, kSearchNormalizedWindow = 2, kSearchFullFrame = 4,
                          kSearchAcquisition = 8, kSkippedFullFrame = 16, kSkippedAcquisition = 32;

/// Detector (reused across frames and cameras) + refinement + cv::undistortPoints.
class FrontEnd {
 public:
  /// `decoder`: libapriltag's decoding table to share with other front ends (TagDetector's
  /// constructor; `detector().decoder()` gives one's to the next), nullptr: its own.
  explicit FrontEnd(DetectorSettings settings = {}, TrackingSettings tracking = {},
                    std::shared_ptr<const TagDecoder> decoder = nullptr);

  /// Runs on one camera's frame. An empty image (camera blind at that frame) gives
  /// detected = false. If `all` is given it receives every decoded tag of the frame (of the
  /// searched window when tracking). With `track`, the search is windowed and the acquisition
  /// pass runs as described at TrackingSettings; without it, one full-frame search.
  Observation observe(const cv::Mat& gray, const io::Calibration& calib,
                      FrameDetections* all = nullptr, TrackState* track = nullptr);
  /// The same for every target of the settings (DetectorSettings::tags_per_target), decided in
  /// one pass per search: one observation per target, in order (observe() returns the first).
  std::vector<Observation> observe_targets(const cv::Mat& gray, const io::Calibration& calib,
                                           FrameDetections* all = nullptr,
                                           TrackState* track = nullptr);
  /// The number of targets observe_targets() reports.
  size_t target_count() const;
  const TrackingSettings& tracking() const { return tracking_; }

  TagDetector& detector() { return detector_; }
  const TagDetector& detector() const { return detector_; }
  const DetectorSettings& settings() const { return detector_.settings(); }

 private:
  /// Whether `gray` is still `reference`'s image (TrackingSettings::change_dn, change_pixels).
  bool unchanged(const cv::Mat& gray, const ChangeReference& reference);

  TagDetector detector_;
  TrackingSettings tracking_;
  cv::Mat difference_;  ///< scratch of unchanged()
};

}  // namespace netvmo::frontend
