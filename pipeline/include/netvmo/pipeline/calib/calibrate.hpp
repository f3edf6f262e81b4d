// `netvmo calibrate`: every camera's pose g_wi from the tags it sees (docs/calibration.md).
//
// Two cases, on the same front end as `run` (frontend::FrontEnd, the same detections and
// refusals):
//  - With a map of static tags (TagMap, read by load_tag_map): each camera's pose from every
//    corner of every map tag it sees over all its frames, jointly, so that a single planar tag's
//    two-fold PnP ambiguity does not decide it. A static camera has one pose g_wi; a moving
//    camera (cameras.csv) has believed poses B_i(t) known up to a rigid registration X_i, and
//    its poses are g_wi(t) = X_i B_i(t) (the renderer's mis-registered world frame,
//    datasets/README.md believed_offset; a static camera is the case B_i = I, X_i = g_wi).
//  - Without a map: a tag or a tag bundle (network.yaml's first target) moved through the rig.
//    Every camera's X_i and the body's pose Y_k = g_wo(t_k) at every moment k seen by two or
//    more cameras are estimated jointly (bundle adjustment), the reference camera held fixed
//    (the gauge). Images are of the same moment when their times (Dataset::frame_time:
//    timestamps.csv, else frame / fps) agree within `same_moment_s`.
//
// Both: initial poses from the project's PnP (frontend::pnp_pose: ViSP's linear poses and
// OpenCV's IPPE solutions, each refined; per frame, the candidate with the smallest robust cost
// over all frames wins), then Ceres minimises the reprojection error of every corner (in
// undistorted pixels: normalized coordinates times fx, fy) under a Huber loss; tag observations
// with a corner beyond the rejection threshold are dropped and the problem solved again. The pose
// covariance is Ceres' (ceres::Covariance, (J^T J)^-1 at the solution) times the residual
// variance sigma^2 = sum r^2 / (m - n), times the design effect of errors that repeat from frame
// to frame (frame_correlation).
//
// Pose perturbation (the covariance's coordinates), order [v; w] as everywhere:
//   X = (R_hat exp(hat(dtheta)), p_hat + dp), dp in the world frame [m], dtheta in the camera
//   frame [rad] (a moving camera: in its believed world frame).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/sources/dataset.hpp"

namespace netvmo::calib {

using Mat6 = Eigen::Matrix<double, 6, 6>;

/// One static tag of a map: its world pose g_wt (netvmo's tag frame, tag_detector.hpp).
struct MapTag {
  std::string family = "tag36h11";
  int id = 0;
  double size = 0.0;                     ///< metres, side of the black border square
  obs::SE3 g_wt = obs::SE3::Identity();  ///< pose of the tag in the world
};

/// A map of static tags (MAP.yaml):
///   tags:
///     - {family: tag36h11, id: 1, size: 0.2, p: [x, y, z], r: [rx, ry, rz]}
///       # or R: [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]] instead of r
/// Read strictly: unknown keys, a missing key, an unsupported family, two families, an id listed
/// twice, a size <= 0, an R that is not orthonormal with det +1 (within 1e-6) and an empty list
/// are an InputError naming the file, the key and the row (tags[k]).
struct TagMap {
  std::vector<MapTag> tags;
  std::string source;  ///< file it was read from
};
TagMap load_tag_map(const std::filesystem::path& file);

/// Settings of a calibration; every default is documented.
struct CalibrationSettings {
  frontend::DetectorSettings detector;  ///< libapriltag and refinement settings (run's defaults)
  frontend::TrackingSettings tracking;  ///< search (run's defaults)
  /// Huber loss scale [px]: corners off by more than this count linearly (robust to bad
  /// detections). 1 px is ~5x the corner noise of clean and realistic rendered images.
  double huber_px = 1.0;
  /// A tag observation is rejected when one of its corners is off by more than
  /// max(reject_sigmas x sigma, reject_min_px) after a solve (sigma: the RMS corner error).
  double reject_sigmas = 5.0;
  double reject_min_px = 1.5;
  int max_rounds = 3;  ///< solve / reject rounds
  /// Only these tag ids (empty: every map tag, or every tag of the moved body).
  std::vector<int> tags;
  /// No-map case: the camera whose pose is held fixed (0: network.yaml's first camera) ...
  int reference_camera = 0;
  /// ... at network.yaml's pose (false: at the identity).
  bool reference_from_network = true;
  /// Two images are of the same moment when their times differ by less than this [s].
  double same_moment_s = 1e-4;
  int max_frames = 0;  ///< 0: every frame of the dataset
};

/// One camera's result.
struct CameraResult {
  int id = 0;
  bool ok = false;
  std::string reason;      ///< why not ok (no tag seen, all rejected, not co-visible, ...)
  bool moving = false;     ///< cameras.csv gives its believed poses: X is a registration
  bool reference = false;  ///< no-map case: the gauge camera (its covariance is zero)
  obs::SE3 X = obs::SE3::Identity();      ///< static: g_wi; moving: g_wi(t) = X B(t)
  obs::SE3 g_wi0 = obs::SE3::Identity();  ///< its pose at frame 0
  Mat6 covariance = Mat6::Zero();         ///< of [dp; dtheta] (header), m^2 / rad^2
  int frames_seen = 0;                    ///< frames with at least one tag used
  int observations_used = 0;              ///< tag observations (4 corners each) in the solution
  int rejected_front_end = 0;             ///< tags the front end refused (border, margin, ...)
  int rejected_outlier = 0;               ///< tag observations dropped as outliers
  double rms_px = 0.0;                    ///< RMS corner reprojection error of those used
  double seconds = 0.0;                   ///< time of its detections and solve
  int images = 0;                         ///< images read (camera-frames)
  /// Initial pose: the naive per-frame OpenCV solvePnP (SQPNP) average, map case only (for
  /// comparison; nullopt when not computed).
  std::optional<obs::SE3> naive_pnp;
  struct Residual {
    int frame = 0;
    int tag = 0;
    int corner = 0;
    double du = 0.0, dv = 0.0;  ///< reprojection minus measurement [undistorted px]
    bool used = true;
  };
  std::vector<Residual> residuals;
  /// How much its corner errors repeat from frame to frame (frame_correlation) and the factor
  /// its covariance was multiplied by for it.
  double frame_correlation = 0.0;
  double covariance_inflation = 1.0;
  /// Standard deviations of [dp (m); dtheta (rad)].
  obs::Vec6 sigmas() const { return covariance.diagonal().cwiseMax(0.0).cwiseSqrt(); }
};

/// Errors that repeat from frame to frame (docs/calibration.md, "Errors that repeat"). A
/// corner's error has a part that comes back in every frame (the print, the lens, the detector's
/// bias at that place in the image) and a part that does not (noise). Frames average the
/// second, not the first, so a covariance that counts every frame as independent shrinks as
/// 1/F while the error does not. From the used residuals grouped by (tag, corner), one-way
/// analysis of variance over both coordinates: the mean squares within and between groups
/// MSW = sum |r - mean_g|^2 / (2 (N - G)), MSB = sum n_g |mean_g - mean|^2 / (2 (G - 1)), and the
/// intraclass correlation rho = (MSB - MSW) / (MSB + (n0 - 1) MSW), n0 = (N - sum n_g^2 / N) /
/// (G - 1), clamped to [0, 1] (N residuals in G groups of n_g). For equicorrelated errors the
/// covariance of a pose fitted to frames of n = N / G observations each grows by the design
/// effect 1 + (n - 1) rho over that of independent frames: rho = 0 leaves it, rho = 1 makes it
/// one frame's. Fewer than two groups, or no group seen twice: rho = 0, inflation 1.
struct FrameCorrelation {
  double rho = 0.0;        ///< intraclass correlation of the residuals, in [0, 1]
  double frames = 1.0;     ///< n = N / G: observations of a corner, on average
  double inflation = 1.0;  ///< 1 + (n - 1) rho
};
FrameCorrelation frame_correlation(const std::vector<CameraResult::Residual>& residuals);

struct CalibrationResult {
  bool with_map = false;
  std::vector<CameraResult> cameras;  ///< in network.yaml order
  double sigma_px = 0.0;              ///< no-map case: the common corner noise estimate
  int moments = 0;                    ///< no-map case: moments seen by two or more cameras
  std::vector<std::string> warnings;
};

/// Runs the calibration on an opened dataset (with a map when `map` is given).
CalibrationResult calibrate(sources::Dataset& ds, const std::optional<TagMap>& map,
                            const CalibrationSettings& s);

/// The network.yaml of the result: `net` with every ok camera's pose at frame 0; cameras that
/// are not ok are left out, and the edges touching them, only when `keep_going` (else an
/// InputError naming them).
io::NetworkConfig calibrated_network(const io::NetworkConfig& net, const CalibrationResult& r,
                                     bool keep_going);

/// Writes into `dir` (an io::OutputDir's folder): network.yaml, calibration.json,
/// residuals_cam_<id>.csv (frame, tag, corner, du, dv, used) and, when some camera moves,
/// cameras.csv with every frame's pose X B(t) (truth_io's format); when a camera was left out
/// and the dataset has timestamps.csv, timestamps.csv without it.
void write_calibration(const std::filesystem::path& dir, sources::Dataset& ds,
                       const CalibrationResult& r, const io::NetworkConfig& calibrated);

/// The line printed for a camera.
std::string camera_line(const CameraResult& c);

}  // namespace netvmo::calib
