// The stages' wall times (steady clock), for the timings a run and a detection report.
#pragma once

#include <chrono>

namespace netvmo {

using Clock = std::chrono::steady_clock;

/// Seconds from t0 to t1 (default: now).
inline double seconds_since(Clock::time_point t0, Clock::time_point t1 = Clock::now()) {
  return std::chrono::duration<double>(t1 - t0).count();
}

}  // namespace netvmo
