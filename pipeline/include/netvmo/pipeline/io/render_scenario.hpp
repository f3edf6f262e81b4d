// Render scenarios: a YAML file describing cameras (true and believed poses, intrinsics,
// distortion), the tagged target and its motion, occluders, lights and imaging settings, loaded
// into render::SceneDescription. The schema is documented in datasets/README.md. Reading is
// strict: an unknown key, a missing value or a non-number is an InputError naming the file and
// the key path (e.g. "datasets/x.yaml: cameras[2].intrinsics.fx: expected a number, got 'abc'").
#pragma once

#include <filesystem>

#include "netvmo/pipeline/io/calibration.hpp"
#include "netvmo/pipeline/io/network_config.hpp"
#include "netvmo/render/scene.hpp"

namespace netvmo::io {

/// Loads and validates a render scenario. OBJ meshes are read relative to the scenario's folder.
render::SceneDescription load_render_scenario(const std::filesystem::path& file);

/// The camera network a scene presents to a run, as network.yaml holds it: believed camera
/// poses, the target tag, the edges and `frames`. Used by the dataset writer and the live source.
NetworkConfig scene_network_config(const render::SceneDescription& scene, int frames);
/// A scene camera's calibration (intrinsics and OpenCV distortion).
Calibration scene_calibration(const render::CameraSpec& camera);

}  // namespace netvmo::io
