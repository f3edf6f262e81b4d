// The paper's Section 5 setup, shared by the observer and runner tests: five cameras, the
// communication graph E = {(1,2),(1,3),(1,5),(2,3),(3,4),(4,5)} (0-based indices here), camera
// positions p_w1 = 0, p_w2 = [1,0,0], p_w3 = [0,1,0], p_w4 = [-1,0,0], p_w5 = [0,-1,0], and the
// fictitious target poses g_wo_1..3 of the cameras that see the target.
#pragma once

#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/lie.hpp"

namespace netvmo::test {

struct Paper5 {
  obs::Graph graph{5, {{0, 1}, {0, 2}, {0, 4}, {1, 2}, {2, 3}, {3, 4}}};
  std::vector<obs::SE3> g_wi;  ///< camera poses
  std::vector<obs::SE3> g_wo;  ///< fictitious targets of cameras 1..3
  /// R_wi = I as printed; `turned`: every camera turned by pi about x, facing the targets.
  explicit Paper5(bool turned = false) {
    const obs::Vec3 p[5] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    const obs::Vec3 r = turned ? obs::Vec3(3.141592653589793, 0, 0) : obs::Vec3::Zero();
    for (const auto& pi : p) g_wi.push_back(obs::make_pose(pi, r));
    g_wo = {obs::make_pose({0.55, 1.00, -1.91}, {0.30, 0.19, 0.21}),
            obs::make_pose({0.30, 0.80, -1.84}, {0.21, 0.30, 0.19}),
            obs::make_pose({0.56, 1.05, -2.00}, {0.29, 0.20, 0.31})};
  }
};

}  // namespace netvmo::test
