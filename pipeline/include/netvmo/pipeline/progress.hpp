// A progress line on stderr for long runs: items done, rate and time left. Redraws in place on
// a terminal; prints a line at most every few seconds otherwise (CI logs stay short).
#pragma once

#include <chrono>
#include <string>

namespace netvmo {

class Progress {
 public:
  Progress(std::string label, long total, bool enabled = true);
  /// Marks `done` items complete (absolute count).
  void update(long done);
  /// Prints the final line with the total time.
  void finish();

 private:
  std::string label_;
  long total_;
  bool enabled_, tty_;
  std::chrono::steady_clock::time_point start_, last_;
  bool finished_ = false;
};

}  // namespace netvmo
