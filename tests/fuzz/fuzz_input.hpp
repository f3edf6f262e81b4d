// Helpers of the libFuzzer targets: the input as a file for readers that take a path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace netvmo::fuzz {

/// This process's scratch folder (created on first use under $TMPDIR, removed at exit).
const std::filesystem::path& scratch_dir();

/// Writes the input to scratch_dir()/name (replacing it) and returns that path. Readers are
/// fuzzed through their real entry point (path in, InputError out); the write costs a few µs.
std::filesystem::path write_input(const std::uint8_t* data, std::size_t size,
                                  const std::string& name);

}  // namespace netvmo::fuzz
