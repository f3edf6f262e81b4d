// A result folder's estimates as TUM trajectory files, the plain-text form that trajectory tools
// (evo, rpg_trajectory_evaluation, the TUM RGB-D benchmark's scripts) read: one line per pose,
//
//   timestamp tx ty tz qx qy qz qw
//
// the time in seconds, the position in metres and the orientation as a unit quaternion (Hamilton,
// scalar last, qw >= 0), the pose being the target's in the world frame (g_wo, DESIGN.md's
// frames). One file per camera (its estimate g_bar_w,i over the frames it has one) and, from the
// dataset's ground truth (target.csv), the true target pose, on the same clock, so that
//
//   evo_ape tum truth.txt cam_1.txt
//
// compares them directly.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/lie.hpp"

namespace netvmo::run {

/// One TUM line (without newline): the time with 6 decimals, position and quaternion with 9.
std::string tum_line(double t, const obs::SE3& g_wo);

/// A pose of a TUM file.
struct TumRow {
  double t = 0.0;
  obs::SE3 g = obs::SE3::Identity();  ///< the quaternion normalised
  int line = 0;                       ///< in its file, from 1
};

/// A trajectory file written by write_trajectories.
struct TrajectoryFile {
  std::string name;          ///< file name in the output folder
  int target = -1;           ///< the target's primary tag id; -1: the run had one target
  int camera = -1;           ///< -1: the ground truth
  std::vector<TumRow> rows;  ///< its poses, one per line, as given (the file rounds them)
};

/// Reads `results`/estimates.csv (netvmo run, demo, launch, merge or simulate) and, with a
/// dataset, its ground truth (target.csv, target_<id>.csv for a later target), and writes into
/// `out`: cam_<id>.txt per camera and truth.txt; with several targets, target_<tag>_cam_<id>.txt
/// and target_<tag>_truth.txt. The truth's times are put on the results' clock (summary.json's
/// time_origin_s): target.csv's times less it where cameras ran on their own clocks, frame / fps
/// where it is null (one clock), as they are without the key. A camera that never had an
/// estimate gets no file.
/// Everything is read and checked before the first file is written (InputError naming the file,
/// line and column; a time that does not increase along a trajectory is one, since TUM tools
/// match poses by time).
std::vector<TrajectoryFile> write_trajectories(const std::filesystem::path& results,
                                               const std::optional<std::filesystem::path>& dataset,
                                               const std::filesystem::path& out);

/// A TUM file: lines of eight numbers separated by spaces or tabs (commas too, as some tools
/// write them); empty lines and lines starting with '#' are skipped. Times must increase, and the
/// quaternion's norm be within 1e-3 of 1 (it is normalised). InputError naming the file and line
/// otherwise, or when the file holds no pose.
std::vector<TumRow> read_tum(const std::filesystem::path& file);

/// How an estimated trajectory is compared with a reference (compare_trajectory).
struct TrajectoryComparisonSettings {
  /// [s] each estimated pose is matched with the reference pose nearest in time, if at most this
  /// far (evo's default t_max_diff).
  double max_dt = 0.01;
  /// [s] added to the reference's times to put them on the results' clock before matching, for
  /// a reference recorded on another clock (motion capture started at another instant): a
  /// reference pose at t_ref is matched as if taken at t_ref + reference_time_offset.
  double reference_time_offset = 0.0;
  /// Align the estimate onto the reference first, for a reference in another frame than the
  /// rig's world (a motion-capture system's): the rigid motion A (no scale) with R_A the chordal
  /// mean of the matched pairs' R_ref R_est^T and t_A the mean of p_ref - R_A p_est. Unlike
  /// evo's --align (Umeyama's, on the positions alone) the rotation comes from the orientations,
  /// so it is determined for a target that barely moves, as netvmo's targets often do.
  /// Off: both are taken in one frame (the dataset's truth).
  bool align = false;
};

/// The absolute trajectory error of an estimate against a reference, over the matched poses:
/// position error |p_ref - (A p_est)| and rotation error angle(R_ref^T R_A R_est), A the
/// alignment.
struct TrajectoryComparison {
  size_t matched = 0;    ///< estimated poses with a reference pose within max_dt
  size_t unmatched = 0;  ///< the others (not in the figures)
  obs::SE3 alignment = obs::SE3::Identity();  ///< A: reference frame <- estimate's frame
  double position_rmse = 0.0, position_mean = 0.0, position_max = 0.0;  ///< [m]
  double rotation_rmse = 0.0, rotation_mean = 0.0, rotation_max = 0.0;  ///< [rad]
};

/// Compares `estimate` with `reference` (both as read_tum gives them; `what` names the pair in
/// errors). InputError when no pose matches, or with `align` when the matched orientations have
/// no unique chordal mean.
TrajectoryComparison compare_trajectory(const std::vector<TumRow>& reference,
                                        const std::vector<TumRow>& estimate,
                                        const TrajectoryComparisonSettings& settings,
                                        const std::string& what);

/// A written camera file against its reference (write_comparisons).
struct CameraComparison {
  std::string file;  ///< the camera's file name in `out`
  int target = -1;   ///< as TrajectoryFile
  int camera = -1;
  std::string reference;  ///< the reference file as given, or the truth's file name in `out`
  TrajectoryComparison comparison;
};

/// Compares every camera trajectory write_trajectories wrote into `out` (`files`) with
/// `reference`, or without it with its target's truth (cameras of a target without one are left
/// out), and writes `out`/comparison.json: the settings and, per camera, the matches, the errors
/// (m, degrees) and the alignment. `reference` needs results of one target (InputError
/// otherwise). Nothing to compare (no reference, no truth written) writes nothing.
std::vector<CameraComparison> write_comparisons(
    const std::filesystem::path& out, const std::vector<TrajectoryFile>& files,
    const std::optional<std::filesystem::path>& reference,
    const TrajectoryComparisonSettings& settings);

}  // namespace netvmo::run
