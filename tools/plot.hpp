// Plots with gnuplot (pngcairo), driven from the CSV files the commands already write.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace netvmo::plot {

/// Runs a gnuplot script that writes to partial_path(png); the PNG is moved into place only
/// when gnuplot succeeds. Throws std::runtime_error naming the plot if gnuplot is missing or
/// fails (then with gnuplot's own message, on one line).
void run_gnuplot(const std::string& script, const std::filesystem::path& png);
std::string partial_path(const std::filesystem::path& png);
/// Quotes a path or text for a gnuplot string literal.
std::string quoted(const std::string& s);

/// One curve: column `y_column` against column `x_column` of a CSV with a header line.
struct Series {
  std::filesystem::path csv;
  std::string title;
  int y_column = 2;
  int x_column = 1;
  std::string style = "lines lw 2";
  /// Only the rows whose column `first` holds the value `second` (e.g. one target's rows).
  std::optional<std::pair<int, double>> where;
};

struct Panel {
  std::string title;
  std::string ylabel;
  bool log_y = false;
  std::vector<Series> series;
  std::optional<std::pair<std::string, double>> reference;  ///< dashed horizontal line
  std::string xlabel = "time [s]";
  bool log_x = false;
};

/// Panels side by side (time on the x axis unless a panel says otherwise).
void panels_figure(const std::vector<Panel>& panels, const std::filesystem::path& png,
                   const std::string& title);

}  // namespace netvmo::plot
