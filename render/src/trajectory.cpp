#include "netvmo/render/trajectory.hpp"

#include <algorithm>
#include <stdexcept>

namespace netvmo::render {

Pose Trajectory::at(double t) const {
  switch (kind) {
    case Kind::Static:
      return g0;
    case Kind::Twist:
      return g0 * exp_se3(t * twist);
    case Kind::Keyframes: {
      if (keyframes.empty()) return g0;
      if (t <= keyframes.front().t) return keyframes.front().g;
      if (t >= keyframes.back().t) return keyframes.back().g;
      const auto it = std::upper_bound(keyframes.begin(), keyframes.end(), t,
                                       [](double tt, const Keyframe& k) { return tt < k.t; });
      const Keyframe& b = *it;
      const Keyframe& a = *(it - 1);
      const double s = (t - a.t) / (b.t - a.t);
      return a.g * exp_se3(s * log_se3(a.g.inverse() * b.g));
    }
  }
  return g0;
}

void Trajectory::validate() const {
  if (kind != Kind::Keyframes) return;
  if (keyframes.empty())
    throw std::invalid_argument("keyframe trajectory needs at least one keyframe");
  for (size_t i = 1; i < keyframes.size(); ++i)
    if (!(keyframes[i].t > keyframes[i - 1].t))
      throw std::invalid_argument("keyframe times must be strictly increasing (keyframe " +
                                  std::to_string(i) + ")");
}

}  // namespace netvmo::render
