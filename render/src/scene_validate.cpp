// Validation of a scene description before anything is built: one std::invalid_argument with
// one line naming the problem.
#include <algorithm>
#include <cmath>
#include <set>
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
      cameras[i].sensor.validate();
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

namespace {
std::vector<const TagSpec*> tags_of(const Target& t) {
  std::vector<const TagSpec*> v{&t.tag};
  for (const auto& e : t.extra_tags) v.push_back(&e.tag);
  return v;
}
}  // namespace

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
  if (targets.empty()) fail("at least one target is required");
  // Tags are told apart by id: a tag of one target may not repeat on another (within a body a
  // repeated id is a decoy the detector must reject, e.g. tag_cube.yaml).
  std::set<std::pair<std::string, int>> earlier;
  for (size_t j = 0; j < targets.size(); ++j) {
    targets[j].motion.validate();
    std::set<std::pair<std::string, int>> own;
    for (const TagSpec* tag : tags_of(targets[j])) {
      if (earlier.count({tag->family, tag->id}))
        fail("targets[" + std::to_string(j) + "]: tag " + tag->family + " id " +
             std::to_string(tag->id) + " is also on an earlier target (tags are told apart by id)");
      own.insert({tag->family, tag->id});
    }
    earlier.insert(own.begin(), own.end());
  }
  for (const auto& b : occluders)
    if (b.motion) b.motion->validate();
  for (const auto& l : lights)
    if (l.kind == Light::Kind::Directional && l.direction.norm() < 1e-12)
      fail("directional light needs a non-zero direction");
}

}  // namespace netvmo::render
