#include "run_plots.hpp"

#include <exception>
#include <fstream>
#include <future>
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

void plot_run(const fs::path& dir, const io::NetworkConfig& net) {
  const fs::path energies = dir / "energies.csv", errors = dir / "errors.csv";
  // Several targets: a `target` column after t selects each target's rows.
  const bool several = net.targets.size() > 1;
  const int shift = several ? 1 : 0;
  const auto series = [&](const fs::path& csv, const std::string& title, int column, size_t j,
                          const std::string& style) {
    plot::Series c{csv, title, column + shift, 2, style, {}};
    if (several) c.where = {{3, net.targets[j].id}};
    return c;
  };
  const auto suffix = [&](size_t j) {
    return several ? ", target " + std::to_string(net.targets[j].id) : std::string();
  };
  static const char* const kColors[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e"};
  // The two figures are drawn by two gnuplot processes at once; an error of the first wins.
  std::future<void> first;
  if (has_rows(energies)) {
    plot::Panel up{"position error energy U_p", "U_p [m^2]", true, {}, {}};
    plot::Panel ur{"orientation error energy U_R", "U_R", true, {}, {}};
    for (size_t j = 0; j < net.targets.size(); ++j) {
      const std::string style = std::string("lines lw 2 lc rgb '") + kColors[j % 4] + "'";
      up.series.push_back(series(energies, "networked observer" + suffix(j), 3, j, style));
      ur.series.push_back(series(energies, "networked observer" + suffix(j), 4, j, style));
    }
    first = std::async(std::launch::async, [=] {
      plot::panels_figure({up, ur}, dir / "energies.png",
                          "Estimation error energies against g*(t)");
    });
  }
  if (has_rows(errors)) {
    plot::Panel pos{"position error to g*", "[mm]", true, {}, {}};
    plot::Panel rot{"orientation error to g*", "[deg]", true, {}, {}};
    for (size_t j = 0; j < net.targets.size(); ++j)
      for (size_t i = 0; i < net.cameras.size(); ++i) {
        const std::string t = "camera " + std::to_string(net.cameras[i].id) + suffix(j);
        const std::string style = j == 0 ? "lines lw 2" : "lines lw 2 dt 2";
        pos.series.push_back(series(errors, t, 3 + 2 * static_cast<int>(i), j, style));
        rot.series.push_back(series(errors, t, 4 + 2 * static_cast<int>(i), j, style));
      }
    std::exception_ptr second;
    try {
      plot::panels_figure({pos, rot}, dir / "errors.png", "Networked observer: error per camera");
    } catch (...) {
      second = std::current_exception();
    }
    if (first.valid()) first.get();
    if (second) std::rethrow_exception(second);
  }
  if (first.valid()) first.get();
}

}  // namespace netvmo::tools
