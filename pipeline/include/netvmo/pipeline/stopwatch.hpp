// The stages' wall times (steady clock), for the timings a run and a detection report, and the
// wall clock that processes on one machine share (epoch seconds: the common start of a launch,
// a live camera's image arrivals).
#pragma once

#include <chrono>

namespace netvmo {

using Clock = std::chrono::steady_clock;

/// Seconds from t0 to t1 (default: now).
inline double seconds_since(Clock::time_point t0, Clock::time_point t1 = Clock::now()) {
  return std::chrono::duration<double>(t1 - t0).count();
}

/// The system clock [s since the epoch].
inline double epoch_seconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace netvmo
