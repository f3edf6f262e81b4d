// Plots of an image run: energies.png and errors.png from energies.csv and errors.csv.
#pragma once

#include <filesystem>

#include "netvmo/pipeline/io/network_config.hpp"

namespace netvmo::tools {

/// energies.png (U_p, U_R against time) and errors.png (each camera's position and orientation
/// error to g* against time), one set of curves per target of `net` (several targets: each
/// selected by the CSVs' `target` column). Skips a plot whose CSV has no data rows (no ground
/// truth).
void plot_run(const std::filesystem::path& dir, const io::NetworkConfig& net);

}  // namespace netvmo::tools
