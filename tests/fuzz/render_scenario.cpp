// Fuzz target: render scenario YAML (io::load_render_scenario, OBJ meshes next to it, the
// scene's validation), then what a run derives from the scene: network.yaml text read back,
// each camera's calibration and the bodies' poses over the run.
#include <fstream>

#include "fuzz_input.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/render_scenario.hpp"

using namespace netvmo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool mesh_written = [] {
    // A mesh a scenario may name (`file: cube.obj`), beside the scenario file.
    std::ofstream(fuzz::scratch_dir() / "cube.obj")
        << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
    return true;
  }();
  (void)mesh_written;
  const auto path = fuzz::write_input(data, size, "scenario.yaml");
  render::SceneDescription scene;
  try {
    scene = io::load_render_scenario(path);
  } catch (const InputError&) {
    return 0;
  }
  const io::NetworkConfig net = io::scene_network_config(scene, scene.frames);
  for (const auto& c : scene.cameras) (void)io::scene_calibration(c);
  const auto yaml_path = fuzz::scratch_dir() / "network.yaml";
  std::ofstream(yaml_path) << io::network_yaml(net);
  (void)io::load_network_config(yaml_path);  // what the scene writes must read back
  const double t_end = scene.frames / scene.fps;
  for (double t : {0.0, 0.5 * t_end, t_end}) {
    (void)scene.target().motion.at(t);
    for (const auto& b : scene.occluders)
      if (b.motion) (void)b.motion->at(t);
  }
  return 0;
}
