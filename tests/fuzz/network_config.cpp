// Fuzz target: a dataset's network.yaml (io::load_network_config). What it accepts must survive
// a round trip through network_yaml() with the same cameras and edges.
#include <fstream>

#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/network_config.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_input(data, size, "network.yaml");
  io::NetworkConfig net;
  try {
    net = io::load_network_config(path);
  } catch (const InputError&) {
    return 0;
  }
  for (const auto& c : net.cameras)
    if (net.index_of(c.id) < 0) __builtin_trap();
  const auto again_path = fuzz::scratch_dir() / "again.yaml";
  std::ofstream(again_path) << io::network_yaml(net);
  const io::NetworkConfig again = io::load_network_config(again_path);
  if (again.cameras.size() != net.cameras.size() || again.edges != net.edges ||
      again.frames != net.frames || again.target().id != net.target().id ||
      again.target().family != net.target().family)
    __builtin_trap();
  return 0;
}
