// Live rendering as a frame source: the Embree renderer draws each camera's frame in memory
// and the run consumes it directly (render + detection + observer, no files).
#pragma once

#include <filesystem>
#include <memory>

#include "netvmo/pipeline/sources/network_source.hpp"
#include "netvmo/render/scene.hpp"

namespace netvmo::sources {

/// A source that renders the scene frame by frame. Ground truth (target and camera poses)
/// comes from the scene. `frames` overrides the scene's frame count when > 0.
std::unique_ptr<NetworkSource> make_render_source(render::SceneDescription scene, int frames = 0);

}  // namespace netvmo::sources
