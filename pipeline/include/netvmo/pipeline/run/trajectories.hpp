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

/// A trajectory file written by write_trajectories.
struct TrajectoryFile {
  std::string name;  ///< file name in the output folder
  int target = -1;   ///< the target's primary tag id; -1: the run had one target
  int camera = -1;   ///< -1: the ground truth
  size_t poses = 0;  ///< lines written
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

}  // namespace netvmo::run
