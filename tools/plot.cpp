#include "plot.hpp"

#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace netvmo::plot {
namespace fs = std::filesystem;

std::string partial_path(const fs::path& png) { return png.string() + ".partial"; }

std::string quoted(const fs::path& p) {
  std::string out = "'";
  for (char c : p.string()) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

void run_gnuplot(const std::string& script, const fs::path& png) {
  FILE* gp = popen("gnuplot 2>&1", "w");
  if (!gp) throw std::runtime_error(png.string() + ": cannot start gnuplot");
  std::fwrite(script.data(), 1, script.size(), gp);
  const int status = pclose(gp);
  std::error_code ec;
  if (status != 0 || !fs::exists(partial_path(png))) {
    fs::remove(partial_path(png), ec);
    throw std::runtime_error(png.string() +
                             ": gnuplot failed (is gnuplot-nox installed? apt-get install "
                             "gnuplot-nox)");
  }
  fs::rename(partial_path(png), png, ec);
  if (ec) throw std::runtime_error(png.string() + ": " + ec.message());
}

namespace {
std::string header(const fs::path& png, int w, int h) {
  std::ostringstream s;
  s << "set terminal pngcairo size " << w << "," << h << " enhanced font 'Sans,10'\n"
    << "set output " << quoted(partial_path(png)) << "\n"
    << "set datafile separator ','\nset key autotitle columnhead\nset grid\n";
  return s.str();
}

std::string using_clause(const Series& s) {
  std::ostringstream u;
  if (s.camera >= 0)
    u << "using 1:($2==" << s.camera << " ? $" << s.column << " : 1/0)";
  else
    u << "using 1:" << s.column;
  return u.str();
}
}  // namespace

void energies_figure(const std::vector<Series>& runs, const fs::path& png,
                     const std::string& title) {
  std::ostringstream s;
  s << header(png, 1100, 450) << "set multiplot layout 1,2 title " << quoted(title) << "\n"
    << "set logscale y\nset format y '10^{%L}'\nset xlabel 'time [s]'\n";
  for (int panel = 0; panel < 2; ++panel) {
    s << "set title " << (panel == 0 ? "'position error energy U_p'" : "'orientation error energy U_R'")
      << "\nplot ";
    for (size_t k = 0; k < runs.size(); ++k) {
      if (k) s << ", ";
      // Clamp at 1e-12 so exact zeros do not vanish from a log axis.
      s << quoted(runs[k].csv) << " using 1:($" << (panel + 2) << " > 1e-12 ? $" << (panel + 2)
        << " : 1e-12) with " << runs[k].style << " title " << quoted(runs[k].title);
    }
    s << "\n";
  }
  s << "unset multiplot\n";
  run_gnuplot(s.str(), png);
}

void series_figure(const std::vector<Series>& series, const fs::path& png,
                   const std::string& title, const std::string& ylabel, bool log_y,
                   const std::string& reference_title, double reference) {
  std::ostringstream s;
  s << header(png, 900, 500) << "set title " << quoted(title) << "\nset xlabel 'time [s]'\n"
    << "set ylabel " << quoted(ylabel) << "\n";
  if (log_y) s << "set logscale y\n";
  s << "plot ";
  for (size_t k = 0; k < series.size(); ++k) {
    if (k) s << ", ";
    s << quoted(series[k].csv) << " " << using_clause(series[k]) << " with " << series[k].style
      << " title " << quoted(series[k].title);
  }
  if (!reference_title.empty())
    s << ", " << reference << " with lines dt 2 lw 2 lc rgb 'red' title " << quoted(reference_title);
  s << "\n";
  run_gnuplot(s.str(), png);
}

}  // namespace netvmo::plot
