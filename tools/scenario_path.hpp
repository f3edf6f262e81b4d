// Default scenario files live in the source tree's datasets/; commands accept a path relative to
// the working directory and fall back to the source tree so the defaults work from anywhere.
#pragma once

#include <filesystem>

namespace netvmo::tools {

inline std::filesystem::path find_scenario(const std::filesystem::path& p) {
  if (std::filesystem::exists(p) || p.is_absolute()) return p;
  const std::filesystem::path in_source = std::filesystem::path(NETVMO_SOURCE_DIR) / p;
  return std::filesystem::exists(in_source) ? in_source : p;
}

}  // namespace netvmo::tools
