// The message of one exchange round (what a camera publishes to its neighbours, mirrored by the
// DDS type of pipeline/src/net/) and the checks a receiver makes of it.
#pragma once

#include <cstdint>

#include "netvmo/observer/estimator.hpp"
#include "netvmo/observer/lie.hpp"

namespace netvmo::obs {

/// What a camera publishes to its neighbours once per exchange round.
struct EstimateMessage {
  int sender = -1;           ///< the publishing camera's index in the network
  std::uint64_t round = 0;   ///< the sender's exchange round (1, 2, ...)
  double stamp = 0.0;        ///< the sender's time of this estimate [s]
  bool initialized = false;  ///< false: the sender has no estimate yet (receivers ignore it)
  /// The sender's boot (incarnation): a restarted sender counts its rounds from 1 again, so a
  /// message of a newer incarnation is accepted whatever its round, one of an older is not.
  std::uint64_t incarnation = 0;
  SE3 g_w = SE3::Identity();  ///< g_wi g_bar_i: the sender's estimate in the world frame
  /// The sender's consensus state (Estimator::state_size() values, the rest zero): zero-offset's
  /// x_i and eta_i. Unused by vmo.
  ConsensusState state{};
};

/// Why receive() refused a message (it is then counted and otherwise ignored).
enum class MessageVerdict {
  accepted,
  not_a_neighbour,  ///< the sender is not in N_i (or is the receiver itself)
  not_finite,       ///< NaN or infinity in the pose or the consensus state
  not_a_rotation,   ///< the rotation block is not orthonormal with determinant +1
  out_of_order      ///< a round not newer than the last one accepted from that sender
};
const char* to_string(MessageVerdict v);

/// The pose check of receive(): accepted, not_finite or not_a_rotation (|R^T R - I| <= 1e-6,
/// det R > 0).
MessageVerdict check_pose(const SE3& g);

}  // namespace netvmo::obs
