// Rigid-body motion over time: static, constant body twist, or keyframes interpolated on SE(3).
#pragma once

#include <vector>

#include "netvmo/render/geometry.hpp"

namespace netvmo::render {

struct Keyframe {
  double t = 0;               ///< time [s]
  Pose g = Pose::Identity();  ///< pose at t
};

struct Trajectory {
  enum class Kind { Static, Twist, Keyframes };
  Kind kind = Kind::Static;
  Pose g0 = Pose::Identity();       ///< Static / Twist: pose at t = 0
  Vec6 twist = Vec6::Zero();        ///< Twist: body twist [v; w] (m/s, rad/s): g(t) = g0 exp(t V^)
  std::vector<Keyframe> keyframes;  ///< Keyframes: strictly increasing t; clamped outside

  /// Pose at time t [s]. Keyframes: g_k exp(s log(g_k^-1 g_k+1)) between keyframes k, k+1.
  Pose at(double t) const;
  /// Throws std::invalid_argument if keyframes are empty or not strictly increasing.
  void validate() const;

  static Trajectory fixed(const Pose& g) {
    Trajectory tr;
    tr.g0 = g;
    return tr;
  }
};

}  // namespace netvmo::render
