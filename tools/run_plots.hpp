// Plots of an image run: energies.png and errors.png from energies.csv and errors.csv.
#pragma once

#include <filesystem>
#include <vector>

namespace netvmo::tools {

/// energies.png (U_p, U_R against time) and errors.png (each camera's position and orientation
/// error to g* against time). Skips a plot whose CSV has no data rows (no ground truth).
void plot_run(const std::filesystem::path& dir, const std::vector<int>& camera_ids);

}  // namespace netvmo::tools
