// The dataset folder's CSV files, read and written here and nowhere else: a rendered dataset's
// ground truth and the front end's detections.csv.
//
//   truth.csv   frame,t,camera,in_fov,visible_fraction,u0,v0,u1,v1,u2,v2,u3,v3
//               corners in OpenCV pixels (libapriltag corner order), empty when the tag is
//               behind the camera
//   target.csv  frame,t,px,py,pz,rx,ry,rz         (g_wo: target position, rotation vector)
//   timestamps.csv  camera,frame,t       (rendered datasets; optional in recorded ones: each
//   image's time [s];
//               frame = the image's index in its camera's folder or video)
//   cameras.csv camera,frame,t,px,py,pz,rx,ry,rz   (optional: believed g_wi per camera image)
//   truth_cameras.csv  the same columns (true g_wi per camera image), or, in older datasets,
//               camera,px,py,pz,rx,ry,rz (one static true pose per camera)
//   detections.csv  frame,camera,tag_id,detected,status,margin,u0,v0,u1,v1,u2,v2,u3,v3,reason
//               one row per camera and frame; status is to_string(TargetStatus) (detected, or
//               the reason the target was not used), reason the same in words (empty when
//               detected); margin and corners empty when detected = 0
//
// And one file of the results: estimates.csv (netvmo run, demo, launch, merge, simulate), each
// camera's estimate of the average target pose in the world, read back by netvmo trajectories.
//
// The header must match exactly; every error is an InputError "<file>:<line>: <column>: ...".
#pragma once

#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/pipeline/target_status.hpp"
#include "netvmo/render/renderer.hpp"

namespace netvmo::io {

struct TruthRow {
  int frame = 0;
  double t = 0.0;
  int camera = 0;
  bool in_fov = false;
  double visible_fraction = 0.0;
  std::optional<std::array<cv::Point2d, 4>> corners;  ///< empty when behind the camera
};

struct TargetTruthRow {
  int frame = 0;
  double t = 0.0;
  obs::SE3 g_wo = obs::SE3::Identity();
};

struct DetectionRow {
  int frame = 0;
  int camera = 0;
  int tag_id = -1;  ///< -1 when not detected (written as empty)
  bool detected = false;
  frontend::TargetStatus status =
      frontend::TargetStatus::not_found;  ///< detected exactly when `detected`
  double margin = 0.0;
  std::optional<std::array<cv::Point2d, 4>> corners;
  /// Why the target was not used (Observation::reason; empty when detected). Written with
  /// every comma replaced by ';' and line breaks by spaces, so it stays one CSV field.
  std::string reason;
};

inline constexpr const char* kTruthHeader =
    "frame,t,camera,in_fov,visible_fraction,u0,v0,u1,v1,u2,v2,u3,v3";
inline constexpr const char* kTargetHeader = "frame,t,px,py,pz,rx,ry,rz";
inline constexpr const char* kDetectionsHeader =
    "frame,camera,tag_id,detected,status,margin,u0,v0,u1,v1,u2,v2,u3,v3,reason";

std::vector<TruthRow> read_truth_csv(const std::filesystem::path& file);
std::vector<TargetTruthRow> read_target_csv(const std::filesystem::path& file);
std::vector<DetectionRow> read_detections_csv(const std::filesystem::path& file);

/// truth_cameras.csv of older datasets: one true (rendering) pose per camera, header
/// camera,px,py,pz,rx,ry,rz (position, rotation vector of R_wi).
inline constexpr const char* kTruthCamerasHeader = "camera,px,py,pz,rx,ry,rz";
struct CameraTruthRow {
  int camera = 0;
  obs::SE3 g_wi = obs::SE3::Identity();
};
std::vector<CameraTruthRow> read_truth_cameras_csv(const std::filesystem::path& file);

/// cameras.csv (believed poses) and truth_cameras.csv (true poses): a camera's pose g_wi at
/// each of its images, header camera,frame,t,px,py,pz,rx,ry,rz (world frame, position and
/// rotation vector of R_wi; t in seconds, for reading only: the run's times come from the
/// images).
inline constexpr const char* kCameraPosesHeader = "camera,frame,t,px,py,pz,rx,ry,rz";
struct CameraPoseRow {
  int camera = 0;
  int frame = 0;  ///< -1: a static pose (truth_cameras.csv of older datasets)
  double t = 0.0;
  obs::SE3 g_wi = obs::SE3::Identity();
  int line = 0;  ///< in the file, for messages
};
/// Reads a camera-pose file and checks what the file alone can tell: camera > 0, frame >= 0,
/// every number finite, no (camera, frame) twice, and every camera with rows has one for each
/// frame from 0 to its last (a missing frame is an error naming the camera and the frame).
/// Rows are returned by camera, then frame. Errors name the file, line and column.
std::vector<CameraPoseRow> read_camera_poses_csv(const std::filesystem::path& file);
/// truth_cameras.csv in either form: per frame (kCameraPosesHeader, read_camera_poses_csv) or
/// one static pose per camera (kTruthCamerasHeader, returned with frame = -1).
std::vector<CameraPoseRow> read_camera_truth_csv(const std::filesystem::path& file);
/// One cameras.csv / truth_cameras.csv line (without newline): t with 6 decimals, the pose with
/// 12 significant digits (as network.yaml, so a static camera's rows read back to the same
/// pose).
std::string format_camera_pose_row(int camera, int frame, double t, const obs::SE3& g_wi);

/// timestamps.csv: the time of every image of a recorded folder, one row per image, header
/// camera,frame,t (seconds; frame = the image's index in its camera's folder or video).
inline constexpr const char* kTimestampsHeader = "camera,frame,t";
struct TimestampRow {
  int camera = 0;
  int frame = 0;
  double t = 0.0;
  int line = 0;  ///< in the file, for messages
};
/// Reads timestamps.csv and checks what the file alone can tell: camera > 0, frame >= 0, t
/// finite, no (camera, frame) twice, and per camera the times strictly increase with the frame.
/// Rows are returned by camera, then frame. Errors name the file, line and column.
std::vector<TimestampRow> read_timestamps_csv(const std::filesystem::path& file);
/// One timestamps.csv line (without newline); t with 17 significant digits, so it reads back
/// to the same double.
std::string format_timestamp_row(int camera, int frame, double t);

/// One truth.csv line (without newline): times with 6 decimals, corners with 4 (a corner behind
/// the camera is written empty).
std::string format_truth_row(const render::FrameTruth& t);
/// The ground-truth file of target `target` in a dataset folder: target.csv for the first,
/// target_<id>.csv (id: its primary tag's; the same columns) for a later one of network.yaml's
/// `targets:`.
std::string target_truth_file(const NetworkConfig& net, size_t target);

/// The ground-truth file of the target whose primary tag is `tag_id` (target_truth_file's rule
/// by the id: `primary` for the first of network.yaml's targets).
std::string target_truth_file(int tag_id, bool primary);

/// estimates.csv of a run on images (run, demo, launch, merge): one row per camera and frame (or
/// per camera image, cameras on their own clocks), with a `target` column (the target's primary
/// tag id) when the run had several targets; the pose (position, rotation vector of R_wo) empty
/// while the camera has no estimate.
inline constexpr const char* kEstimatesHeader = "frame,t,camera,delta,px,py,pz,rx,ry,rz";
inline constexpr const char* kEstimatesTargetsHeader =
    "frame,t,target,camera,delta,px,py,pz,rx,ry,rz";
/// estimates.csv of netvmo simulate: t,camera and the pose.
inline constexpr const char* kSimulationEstimatesHeader = "t,camera,px,py,pz,rx,ry,rz";
struct EstimateRow {
  int frame = -1;   ///< -1: not in the file (simulate)
  double t = 0.0;   ///< [s]
  int target = -1;  ///< the target's primary tag id; -1: one target (no target column)
  int camera = 0;
  bool delta = false;           ///< the camera detected the target (false where not in the file)
  std::optional<obs::SE3> g_w;  ///< the camera's estimate g_bar_w,i; empty: none yet
  int line = 0;                 ///< in the file, for messages
};
/// Reads estimates.csv in any of its three forms (by its header). Errors name the file, line and
/// column: a header that is none of the three, a field that is not a number, a camera id <= 0,
/// a pose given in part.
std::vector<EstimateRow> read_estimates_csv(const std::filesystem::path& file);

/// One target.csv line (without newline): position and rotation vector with 9 digits.
std::string format_target_row(int frame, double t, const obs::SE3& g_wo);
/// One truth_cameras.csv line (without newline).
std::string format_truth_camera_row(int camera, const obs::SE3& g_wi);
/// One detections.csv line (without newline). Corners with 4 decimals, margin with 2.
std::string format_detection_row(const DetectionRow& row);

}  // namespace netvmo::io
