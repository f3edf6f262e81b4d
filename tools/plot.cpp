#include "plot.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace netvmo::plot {
namespace fs = std::filesystem;

std::string partial_path(const fs::path& png) {
  return png.string() + ".partial";
}

std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

void run_gnuplot(const std::string& script, const fs::path& png) {
  // The script goes through a file so that gnuplot's own messages can be read back: a failure
  // is reported with them, and "not installed" only when the shell cannot find gnuplot.
  const std::string script_file = partial_path(png) + ".gp";
  std::error_code ec;
  {
    std::FILE* f = std::fopen(script_file.c_str(), "w");
    if (!f) throw std::runtime_error(png.string() + ": cannot write " + script_file);
    std::fwrite(script.data(), 1, script.size(), f);
    std::fclose(f);
  }
  std::string shell_quoted = "'";
  for (char c : script_file) shell_quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  shell_quoted += "'";
  FILE* gp = popen(("gnuplot " + shell_quoted + " 2>&1").c_str(), "r");
  if (!gp) {
    fs::remove(script_file, ec);
    throw std::runtime_error(png.string() + ": cannot start gnuplot");
  }
  std::string output;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, gp)) > 0;) output.append(buf, n);
  const int status = pclose(gp);
  fs::remove(script_file, ec);
  const bool ok = status == 0 && fs::exists(partial_path(png));
  if (!ok) {
    fs::remove(partial_path(png), ec);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
      throw std::runtime_error(png.string() + ": gnuplot not found (apt-get install gnuplot-nox)");
    // gnuplot's own message, on one line: its non-blank lines, the last few.
    std::vector<std::string> lines;
    std::istringstream in(output);
    for (std::string l; std::getline(in, l);) {
      const size_t a = l.find_first_not_of(" \t\r^"), b = l.find_last_not_of(" \t\r");
      if (a != std::string::npos) lines.push_back(l.substr(a, b - a + 1));
    }
    std::string msg;
    for (size_t i = lines.size() > 3 ? lines.size() - 3 : 0; i < lines.size(); ++i)
      msg += (msg.empty() ? "" : " | ") + lines[i];
    if (msg.empty())
      msg = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                              : std::string("killed by a signal");
    throw std::runtime_error(png.string() + ": gnuplot failed: " + msg);
  }
  fs::rename(partial_path(png), png, ec);
  if (ec) throw std::runtime_error(png.string() + ": " + ec.message());
}

void panels_figure(const std::vector<Panel>& panels, const fs::path& png,
                   const std::string& title) {
  std::ostringstream s;
  const int width = 550 * static_cast<int>(panels.size()) + 100;
  s << "set terminal pngcairo size " << width << ",480 enhanced font 'Sans,10'\n"
    << "set output " << quoted(partial_path(png)) << "\n"
    << "set datafile separator ','\nset grid\nset key top right\n"
    << "set multiplot layout 1," << panels.size() << " title " << quoted(title) << "\n";
  for (const auto& p : panels) {
    s << "set title " << quoted(p.title) << "\nset ylabel " << quoted(p.ylabel) << "\n"
      << "set xlabel " << quoted(p.xlabel) << "\n"
      << (p.log_x ? "set logscale x\n" : "unset logscale x\n");
    if (p.log_y)
      s << "set logscale y\nset format y '10^{%L}'\n";
    else
      s << "unset logscale y\nset format y '%g'\n";
    s << "plot ";
    for (size_t k = 0; k < p.series.size(); ++k) {
      const auto& c = p.series[k];
      if (k) s << ", ";
      // On a log axis, clamp at 1e-12 so exact zeros do not vanish.
      s << quoted(c.csv.string()) << " every ::1 using " << c.x_column << ":";
      // Rows filtered out are undefined (1/0): gnuplot skips them.
      std::string open, close;
      if (c.where) {
        char b[64];
        std::snprintf(b, sizeof b, "($%d == %.17g ? ", c.where->first, c.where->second);
        open = b;
        close = " : 1/0)";
      }
      if (p.log_y)
        s << open << "($" << c.y_column << " > 1e-12 ? $" << c.y_column << " : 1e-12)" << close;
      else if (c.where)
        s << open << "$" << c.y_column << close;
      else
        s << c.y_column;
      s << " with " << c.style << " title " << quoted(c.title);
    }
    if (p.reference)
      s << ", " << p.reference->second << " with lines dt 2 lw 2 lc rgb 'red' title "
        << quoted(p.reference->first);
    s << "\n";
  }
  s << "unset multiplot\n";
  run_gnuplot(s.str(), png);
}

}  // namespace netvmo::plot
