#include "run_plots.hpp"

#include <fstream>
#include <string>

#include "plot.hpp"

namespace netvmo::tools {
namespace fs = std::filesystem;

namespace {
bool has_rows(const fs::path& csv) {
  std::ifstream f(csv);
  std::string line;
  return std::getline(f, line) && std::getline(f, line) && !line.empty();
}
}  // namespace

void plot_run(const fs::path& dir, const std::vector<int>& camera_ids) {
  const fs::path energies = dir / "energies.csv", errors = dir / "errors.csv";
  if (has_rows(energies)) {
    plot::Panel up{"position error energy U_p",
                   "U_p [m^2]",
                   true,
                   {{energies, "networked observer", 3, 2, "lines lw 2 lc rgb '#d62728'"}},
                   {}};
    plot::Panel ur{"orientation error energy U_R",
                   "U_R",
                   true,
                   {{energies, "networked observer", 4, 2, "lines lw 2 lc rgb '#d62728'"}},
                   {}};
    plot::panels_figure({up, ur}, dir / "energies.png", "Estimation error energies against g*(t)");
  }
  if (has_rows(errors)) {
    plot::Panel pos{"position error to g*", "[mm]", true, {}, {}};
    plot::Panel rot{"orientation error to g*", "[deg]", true, {}, {}};
    for (size_t i = 0; i < camera_ids.size(); ++i) {
      const std::string t = "camera " + std::to_string(camera_ids[i]);
      pos.series.push_back({errors, t, 3 + 2 * static_cast<int>(i), 2, "lines lw 2"});
      rot.series.push_back({errors, t, 4 + 2 * static_cast<int>(i), 2, "lines lw 2"});
    }
    plot::panels_figure({pos, rot}, dir / "errors.png", "Networked observer: error per camera");
  }
}

}  // namespace netvmo::tools
