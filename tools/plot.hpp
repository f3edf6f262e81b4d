// Plots with gnuplot (pngcairo), driven from the CSV files the commands already write.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace netvmo::plot {

/// Runs a gnuplot script that writes `png` (the script must `set output` to the path returned
/// by partial_path(png)); the PNG is moved into place only when gnuplot succeeds. Throws
/// std::runtime_error naming the plot if gnuplot is missing or fails.
void run_gnuplot(const std::string& script, const std::filesystem::path& png);
std::string partial_path(const std::filesystem::path& png);

/// Quotes a path for a gnuplot string literal.
std::string quoted(const std::filesystem::path& p);

/// One curve of a per-camera series in a long CSV (columns t, camera, ...).
struct Series {
  std::filesystem::path csv;
  std::string title;
  int column = 3;   ///< 1-based column with the value
  int camera = -1;  ///< filter on column 2 == camera; -1 = no filter
  std::string style = "lines lw 2";
};

/// Fig. 5 of the paper: U_p and U_R against time on log scales, one panel each.
/// `runs` are (energies.csv, title, style) for each run drawn.
void energies_figure(const std::vector<Series>& runs, const std::filesystem::path& png,
                     const std::string& title);

/// A time plot of several series, with an optional horizontal dashed reference line.
void series_figure(const std::vector<Series>& series, const std::filesystem::path& png,
                   const std::string& title, const std::string& ylabel, bool log_y = false,
                   const std::string& reference_title = "", double reference = 0.0);

}  // namespace netvmo::plot
