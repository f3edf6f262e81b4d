#include "netvmo/observer/estimate_message.hpp"

#include "pose_kernel.hpp"

namespace netvmo::obs {

const char* to_string(MessageVerdict v) {
  switch (v) {
    case MessageVerdict::accepted:
      return "accepted";
    case MessageVerdict::not_a_neighbour:
      return "not a neighbour";
    case MessageVerdict::not_finite:
      return "pose not finite";
    case MessageVerdict::not_a_rotation:
      return "rotation not orthonormal";
    case MessageVerdict::out_of_order:
      return "out of order";
  }
  return "?";
}

MessageVerdict check_pose(const SE3& g) {
  return kernel::check_pose(kernel::pose_of(g));
}

}  // namespace netvmo::obs
