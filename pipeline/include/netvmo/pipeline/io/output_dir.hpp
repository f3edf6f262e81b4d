// A command's whole output folder, built in a temporary sibling and swapped into place at the
// end, under a lock, so that a run killed at any point (even by SIGKILL) leaves the previous
// result under the folder's name intact and complete, and two runs never write the same folder.
//
// For an output folder DIR (DIR's parent is created if needed):
//  - DIR.lock (a sibling, so its path does not depend on the folder being replaced) is locked
//    with flock(LOCK_EX); the kernel releases it when the process ends, however it ends. A
//    second command finding it locked fails with one line: "another netvmo run (pid N) is
//    writing DIR". The lock file holds "PID COMMAND" and is left in place (removing it would
//    let a third process lock a new file while the second holds the old one).
//  - Holding the lock, siblings named DIR.partial-<pid> are stale (left by a killed run) and
//    removed; with `resume`, the newest one without the marker (a killed run's unfinished
//    folder, e.g. a node's journal) is renamed to this run's temporary folder and kept.
//  - An existing DIR must be a folder that is empty or was written by the same netvmo command
//    (it holds the marker file `.netvmo-output` naming the command, or, written before the
//    marker existed, every file that command always writes); anything else is refused, so that
//    `--out ~` never replaces a folder of the user's.
//  - The command writes into path() = DIR.partial-<pid>. commit() writes the marker, then
//    renameat2(RENAME_EXCHANGE) swaps the two folders in one step (or rename() when DIR does not
//    exist), then removes the old result (now under the temporary name).
//  - Destroyed without commit() (an error), the temporary folder is removed; DIR is untouched.
// Not covered: power loss (nothing is fsync'ed).
#pragma once

#include <filesystem>
#include <string>

namespace netvmo::io {

/// The marker file commit() leaves in every output folder (content: the command's name).
inline constexpr const char* kOutputMarker = ".netvmo-output";

class OutputDir {
 public:
  /// Locks `dir` for `command` (e.g. "run"), cleans stale temporary siblings and creates the
  /// temporary folder (with `resume`: takes over a killed run's unfinished one, if any). Throws
  /// InputError (one line naming dir) when another process holds the lock, when dir exists and
  /// is not a netvmo output folder, or on a file system error.
  OutputDir(std::filesystem::path dir, std::string command, bool resume = false);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Where the command writes its outputs until commit().
  const std::filesystem::path& path() const { return staging_; }
  /// The folder's final name.
  const std::filesystem::path& final_path() const { return dir_; }
  /// Puts the finished folder in place atomically and removes the previous one.
  void commit();
  /// After a failure: moves the unfinished folder to DIR.failed (replacing an older one) for
  /// the user to inspect (e.g. logs); DIR is untouched. Returns DIR.failed.
  std::filesystem::path keep_failed();

 private:
  std::filesystem::path dir_, staging_, lock_;
  std::string command_;
  int lock_fd_ = -1;
  bool committed_ = false;
};

/// Refuses (InputError, one line) an output folder that equals the input dataset folder or lies
/// inside it, or a dataset folder inside the output folder (replacing the output would delete
/// it), and an output folder inside any folder that holds a network.yaml (a dataset). `input`
/// names the input folder in the message (e.g. "NODES folder" for merge's node outputs).
void check_output_apart(const std::filesystem::path& out, const std::filesystem::path& dataset,
                        const std::string& option = "--out",
                        const std::string& input = "dataset folder");

/// The sibling lock file of an output folder (DIR.lock).
std::filesystem::path lock_path(const std::filesystem::path& dir);

}  // namespace netvmo::io
