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

/// How a reference's time offset is estimated (estimate_time_offset). The defaults suit a
/// motion-capture reference of a target moved by hand for a few seconds, against estimates at
/// camera frame rates.
struct TimeOffsetSettings {
  /// [s] the offsets tried: reference_time_offset within +-search of `centre`.
  double search = 1.0;
  /// [s] the middle of the offsets tried (a rough offset known beforehand).
  double centre = 0.0;
  /// [s] the spacing of the offsets tried; 0: a quarter of the estimates' median time step.
  double step = 0.0;
  /// [s] the speeds are taken over poses at least this far apart: the noise of an estimate's
  /// speed is its pose noise divided by this time, over one frame three times what it is here.
  double baseline = 0.1;
  /// The offset counts as determined only where the mismatch at the best offset is at most this
  /// fraction of its median over the offsets tried. A target that barely moves, or whose speed
  /// changes by less than the estimates' noise, leaves the mismatch flat.
  double max_contrast = 0.5;
  /// An offset is judged only where the reference covers at least this fraction of the
  /// estimates' pose pairs.
  double min_overlap = 0.5;
};

/// What estimate_time_offset found.
struct TimeOffsetEstimate {
  double offset = 0.0;           ///< [s] the reference_time_offset that matches the speeds best
  double mismatch = 0.0;         ///< the speeds' mismatch there (see estimate_time_offset)
  double median_mismatch = 0.0;  ///< its median over the offsets tried
  size_t pairs = 0;              ///< the estimates' pose pairs compared at the offset found
  size_t offsets = 0;            ///< the offsets tried that the reference covered
  double position_noise = 0.0;   ///< [m] the estimates' pose noise per axis, as read (see below)
  double rotation_noise = 0.0;   ///< [rad] the same of the orientation
};

/// The time offset between a reference recorded on another clock and the estimates: the
/// reference_time_offset (TrajectoryComparisonSettings) at which the target's speeds agree best.
/// The linear speed |p(t2) - p(t1)| / (t2 - t1) and the angular speed |log(R(t1)^T R(t2))| /
/// (t2 - t1) are the same in any world frame, so no alignment is needed first. For every pair of
/// an estimate's poses `baseline` apart (no pair across a gap of over 3 median steps more) the
/// reference is interpolated at both times less the offset (on the SE(3) geodesic between the
/// poses around each, sources::pose_at, as the renderer's keyframes; not across a gap of over 3 of
/// its median steps), and the mismatch
/// is the mean over the pairs of both speeds' squared differences, each in units of the
/// reference's own speed spread (its standard deviation over its span, at the baseline) and
/// capped at 9 (three spreads: a camera's start-up transient is no motion of the reference's).
/// The estimates' speeds are first freed of their noise's bias: noise of variance s^2 per axis
/// on both poses raises a pair's squared displacement by 6 s^2 on average, and s^2 is read off
/// the estimates themselves (the median residual of a quadratic in time fitted to every 5
/// consecutive poses, per axis of the position and of the rotation vector from the middle pose;
/// noise correlated over 5 poses, a filter's, is read as motion). The reference is taken as
/// exact. A speed the reference keeps within a thousandth of its mean is left out. The speeds
/// are compared as they are, not correlated: a correlation ignores their scale, and a shifted
/// exponential convergence is the same one scaled. Tried on a grid, the best offset is refined
/// by a parabola through its neighbours. The offset found also holds any lag of
/// the estimates behind the motion (an observer's tracking delay). InputError (naming `what`)
/// where the reference's speeds do not change, where it covers fewer than 3 of the offsets,
/// where the best offset lies at the edge of the search, or its mismatch exceeds max_contrast of
/// the median.
TimeOffsetEstimate estimate_time_offset(const std::vector<TumRow>& reference,
                                        const std::vector<const std::vector<TumRow>*>& estimates,
                                        double max_dt, const TimeOffsetSettings& settings,
                                        const std::string& what);

/// A written camera file against its reference (write_comparisons).
struct CameraComparison {
  std::string file;  ///< the camera's file name in `out`
  int target = -1;   ///< as TrajectoryFile
  int camera = -1;
  std::string reference;  ///< the reference file as given, or the truth's file name in `out`
  TrajectoryComparison comparison;
};

/// What write_comparisons compared.
struct Comparisons {
  std::vector<CameraComparison> cameras;
  /// The reference's time offset where it was estimated (then the one every camera was compared
  /// at).
  std::optional<TimeOffsetEstimate> time_offset;
};

/// Compares every camera trajectory write_trajectories wrote into `out` (`files`) with
/// `reference`, or without it with its target's truth (cameras of a target without one are left
/// out), and writes `out`/comparison.json: the settings and, per camera, the matches, the errors
/// (m, degrees) and the alignment. `reference` needs results of one target (InputError
/// otherwise). With `estimate_offset` (which needs `reference`), the reference's time offset is
/// first estimated from every camera's file at once (estimate_time_offset, centred on
/// settings.reference_time_offset) and the cameras are compared at it; comparison.json then also
/// has what the estimate found. Nothing to compare (no reference, no truth written) writes
/// nothing.
Comparisons write_comparisons(
    const std::filesystem::path& out, const std::vector<TrajectoryFile>& files,
    const std::optional<std::filesystem::path>& reference, TrajectoryComparisonSettings settings,
    const std::optional<TimeOffsetSettings>& estimate_offset = std::nullopt);

}  // namespace netvmo::run
