// Validation of a scene description before anything is built: one std::invalid_argument with
// one line naming the problem.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "netvmo/render/scene.hpp"

namespace netvmo::render {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument(what);
}

void validate_cameras(const std::vector<CameraSpec>& cameras) {
  if (cameras.empty()) fail("the scene has no cameras");
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].id <= 0)
      fail("camera ids must be positive integers (got " + std::to_string(cameras[i].id) + ")");
    for (size_t j = 0; j < i; ++j)
      if (cameras[j].id == cameras[i].id)
        fail("duplicate camera id " + std::to_string(cameras[i].id));
    try {
      cameras[i].intrinsics.validate();
      if (cameras[i].motion) cameras[i].motion->validate();
    } catch (const std::invalid_argument& e) {
      fail("camera " + std::to_string(cameras[i].id) + ": " + e.what());
    }
    if (!cameras[i].believed_drift.allFinite())
      fail("camera " + std::to_string(cameras[i].id) + ": believed_drift must be finite");
  }
}

void validate_edges(const std::vector<CameraSpec>& cameras,
                    const std::vector<std::pair<int, int>>& edges) {
  auto known = [&](int id) {
    return std::any_of(cameras.begin(), cameras.end(),
                       [&](const CameraSpec& c) { return c.id == id; });
  };
  for (const auto& e : edges)
    if (!known(e.first) || !known(e.second) || e.first == e.second)
      fail("edge [" + std::to_string(e.first) + ", " + std::to_string(e.second) +
           "] must join two different known cameras");
}

void validate_imaging(const Imaging& im) {
  if (im.spp < 1 || im.spp > 1024) fail("spp must be between 1 and 1024");
  if (im.tile < 1) fail("tile must be positive");
  if (im.threads < 0) fail("threads must be >= 0");
  if (im.visibility_grid < 1) fail("visibility_grid must be positive");
  if (im.read_noise < 0 || im.shot_noise < 0) fail("noise levels must be >= 0");
}

}  // namespace

bool SceneDescription::one_clock() const {
  for (const auto& c : cameras)
    if ((c.fps && *c.fps != fps) || c.start != 0.0) return false;
  return true;
}

std::vector<double> SceneDescription::image_times(size_t ci, int n) const {
  const CameraSpec& c = cameras.at(ci);
  std::vector<double> t;
  if (!c.fps && c.start == 0.0) {  // the scene's clock, written as Renderer::time_of does
    for (int k = 0; k < n; ++k) t.push_back(k / fps);
    return t;
  }
  const double f = c.fps.value_or(fps), end = n / fps;
  for (int k = 0;; ++k) {
    const double tk = c.start + k / f;
    if (!(tk < end - 1e-9)) break;
    t.push_back(tk);
  }
  return t;
}

void SceneDescription::validate() const {
  validate_cameras(cameras);
  for (const auto& c : cameras) {
    if (c.fps && !(*c.fps > 0 && std::isfinite(*c.fps)))
      fail("camera " + std::to_string(c.id) + ": fps must be positive");
    if (!(c.start >= 0 && std::isfinite(c.start)))
      fail("camera " + std::to_string(c.id) + ": start must be >= 0 s");
  }
  validate_edges(cameras, edges);
  if (!(fps > 0)) fail("fps must be positive");
  if (frames < 1) fail("frames must be at least 1");
  validate_imaging(imaging);
  target.motion.validate();
  for (const auto& b : occluders)
    if (b.motion) b.motion->validate();
  for (const auto& l : lights)
    if (l.kind == Light::Kind::Directional && l.direction.norm() < 1e-12)
      fail("directional light needs a non-zero direction");
}

}  // namespace netvmo::render
