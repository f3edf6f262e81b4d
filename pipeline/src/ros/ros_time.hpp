// builtin_interfaces/msg/Time <-> nanoseconds, for the message encoders of src/ros/.
#pragma once

#include <cstdint>

#include "PoseStamped.h"

namespace netvmo::ros::detail {

inline builtin_interfaces_msg_dds__Time_ time_of(std::int64_t ns) {
  builtin_interfaces_msg_dds__Time_ t{};
  std::int64_t sec = ns / 1'000'000'000, rest = ns % 1'000'000'000;
  if (rest < 0) {
    rest += 1'000'000'000;
    --sec;
  }
  t.sec = static_cast<int32_t>(sec);
  t.nanosec = static_cast<uint32_t>(rest);
  return t;
}

inline std::int64_t ns_of(const builtin_interfaces_msg_dds__Time_& t) {
  return std::int64_t{t.sec} * 1'000'000'000 + t.nanosec;
}

}  // namespace netvmo::ros::detail
