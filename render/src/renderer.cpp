// The renderer's construction and frame state: the scene is validated and built once
// (scene_validate.cpp, scene_build.cpp), each camera's rays prepared (camera_rays.cpp); per
// frame, only the instances' transforms change and the top-level scene is recommitted. Images
// come from render_loop.cpp, ground truth from ground_truth.cpp.
#include "netvmo/render/renderer.hpp"

#include <stdexcept>

#include "renderer_impl.hpp"

namespace netvmo::render {

Renderer::Renderer(SceneDescription scene)
    : scene_(std::move(scene)), impl_(std::make_unique<Impl>()) {
  scene_.validate();
  Impl& I = *impl_;
  I.build(scene_);
  I.offsets = sample_offsets(scene_.imaging.spp);
  for (const auto& cam : scene_.cameras) {
    I.cams.push_back(
        make_camera_cache(cam.intrinsics, I.offsets, pixel_jitter_key(scene_.imaging, cam.id)));
    I.radiance.push_back(std::make_unique<RadianceCache>());
  }
  set_frame(0);
}

Renderer::~Renderer() = default;

int Renderer::camera_index(int id) const {
  for (size_t i = 0; i < scene_.cameras.size(); ++i)
    if (scene_.cameras[i].id == id) return int(i);
  throw std::invalid_argument("unknown camera id " + std::to_string(id));
}

Pose Renderer::target_pose(int frame, size_t target) const {
  return scene_.targets.at(target).motion.at(time_of(frame));
}

Pose Renderer::camera_pose(int ci, int frame) const {
  return scene_.cameras.at(size_t(ci)).true_pose(time_of(frame));
}

Pose Renderer::believed_camera_pose(int ci, int frame) const {
  return scene_.cameras.at(size_t(ci)).believed_pose(time_of(frame));
}

void Renderer::set_frame_times(std::vector<double> times) {
  frame_times_ = std::move(times);
  impl_->current_frame = -1;  // the current frame's time may have changed
  set_frame(0);
}

void Renderer::set_frame(int frame) {
  std::unique_lock<std::shared_mutex> lock(impl_->mutex);
  Impl& I = *impl_;
  if (I.current_frame == frame) return;
  const double t = time_of(frame);
  for (auto& in : I.instances) {
    if (I.blurred(in))
      I.set_motion(in, *in.motion, t);
    else if (in.motion)
      I.set_transform(in, in.motion->at(t));
  }
  rtcCommitScene(I.top);
  I.check("per-frame commit");
  I.current_frame = frame;
}

namespace {
// Holds a shared lock on the renderer's frame state with `frame` current.
template <class SetFrame>
std::shared_lock<std::shared_mutex> lock_frame(std::shared_mutex& m, const int& current, int frame,
                                               SetFrame&& set_frame) {
  for (;;) {
    std::shared_lock<std::shared_mutex> lk(m);
    if (current == frame) return lk;
    lk.unlock();
    set_frame(frame);
  }
}
}  // namespace

std::shared_lock<std::shared_mutex> Renderer::acquire(int ci, int frame) {
  if (ci < 0 || ci >= camera_count()) throw std::invalid_argument("camera index out of range");
  if (frame < 0) throw std::invalid_argument("frame must be >= 0");
  return lock_frame(impl_->mutex, impl_->current_frame, frame, [this](int f) { set_frame(f); });
}

}  // namespace netvmo::render
