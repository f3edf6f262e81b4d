// The paper's "Verification through simulation": a static target seen by some cameras through
// their fictitious target poses g_wo_i, the networked observer run on exact poses or on the
// projected feature points, and the paper's metrics over time.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/observer/graph.hpp"
#include "netvmo/observer/metrics.hpp"
#include "netvmo/observer/networked_observer.hpp"

namespace netvmo::sim {

using obs::SE3;

struct SimCamera {
  int id = 0;                  ///< user-facing camera id (as in the scenario file)
  SE3 g_wi = SE3::Identity();  ///< camera pose in the world
  std::optional<SE3> g_wo;     ///< fictitious target pose o_i in the world; none = never sees it
};

/// A simulation scenario (datasets/paper5.yaml documents the file format).
struct SimScenario {
  std::string name;
  double fps = 30.0;       ///< observer update rate (frames per second)
  double duration = 20.0;  ///< simulated seconds
  double k_e = 1.0;        ///< visual feedback gain
  double k_s = 50.0;       ///< mutual feedback gain
  /// Visual error model (observer/error_model.hpp): exact or jacobian. A simulation gives every
  /// camera its true relative pose and its projected features, not a PnP pose.
  std::string error_model = "exact";
  /// The networked estimator (observer/estimator.hpp): vmo (the paper's) or zero-offset.
  std::string estimator = "vmo";
  double square_side = 0.2;       ///< side of the m = 4 point square used by the jacobian model (m)
  SE3 initial = SE3::Identity();  ///< g_bar_i(0), the same in every camera's frame
  std::vector<SimCamera> cameras;
  std::vector<std::pair<int, int>> edges;  ///< camera indices (0-based)
};

/// Loads and validates a scenario. Throws InputError naming the file and key on any problem,
/// including a disconnected graph (naming its components) or an unknown camera id in edges.
SimScenario load_scenario(const std::filesystem::path& file);

/// Time series of a run.
struct SimResult {
  SE3 g_star = SE3::Identity();
  obs::Spread spread;
  obs::PaperW W;
  int diameter = 0;
  int substeps = 0;
  std::vector<double> t;
  std::vector<obs::Energies> energies;            ///< per sample
  std::vector<std::vector<SE3>> estimates_world;  ///< per sample, per camera
  obs::EpsLevels eps_final;                       ///< at the final time
  obs::EpsLevels eps_tail;  ///< sup over the last quarter of the run (T = 3/4 duration)
};

SimResult simulate(const SimScenario& s);

/// Writes energies.csv, estimates.csv, orientation_x.csv and summary.json into dir (atomically).
void write_outputs(const SimScenario& s, const SimResult& r, const std::filesystem::path& dir);

/// Why a simulation cannot use the named error model (unknown, or it reads a measured pose),
/// or an empty string when it can.
std::string simulation_error_model_problem(const std::string& name);

}  // namespace netvmo::sim
