// Scene building: the Embree device, triangle meshes with their materials and tag textures,
// one instance for all static geometry (built once), one per target and one per moving
// occluder, all attached to the small top-level scene that is recommitted per frame.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

std::string device_error_text(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE:
      return "none";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

Mesh shape_mesh(const Shape& s) {
  switch (s.kind) {
    case Shape::Kind::Box:
      return make_box(s.size);
    case Shape::Kind::Plane:
      return make_plane(s.size.x(), s.size.y());
    case Shape::Kind::Cylinder:
      return make_cylinder(s.size.x(), s.size.z(), s.segments);
    case Shape::Kind::Mesh:
      return s.mesh;
  }
  return Mesh();
}

}  // namespace

Renderer::Impl::~Impl() {
  for (auto& in : instances) {
    if (in.geom) rtcReleaseGeometry(in.geom);
    if (in.scene) rtcReleaseScene(in.scene);
  }
  if (top) rtcReleaseScene(top);
  if (device) rtcReleaseDevice(device);
}

void Renderer::Impl::check(const char* what) const {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("Embree error in ") + what + ": " + device_error_text(e));
}

void Renderer::Impl::create_device() {
  device = rtcNewDevice(nullptr);
  if (!device)
    throw std::runtime_error("cannot create the Embree device: " +
                             device_error_text(rtcGetDeviceError(nullptr)));
  top = rtcNewScene(device);
  rtcSetSceneFlags(top, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(top, RTC_BUILD_QUALITY_LOW);
}

double motion_half_window(const SceneDescription& scene) {
  double w = 0;
  for (const auto& c : scene.cameras)
    w = std::max(w, 0.5 * c.sensor.exposure_time +
                        std::abs(c.sensor.line_delay) * 0.5 * (c.intrinsics.height - 1));
  return w;
}

void Renderer::Impl::build(const SceneDescription& scene) {
  half_window = motion_half_window(scene);
  motion_steps = half_window > 0 ? kMotionSteps : 1;
  create_device();
  instances.reserve(1 + scene.targets.size() + scene.occluders.size());
  // Static geometry: one scene, built once, instanced with the identity.
  bool any_static = false;
  for (const auto& b : scene.occluders) any_static |= !b.motion && !b.shapes.empty();
  if (any_static) {
    Instance& st = new_instance("static");
    for (const auto& b : scene.occluders)
      if (!b.motion)
        for (const auto& s : b.shapes) add_shape(st, s);
    attach_instance(st, int(instances.size() - 1));
  }
  // The targets, one instance each.
  for (const Target& target : scene.targets) {
    Instance& tg = new_instance("target");
    add_tag(tg, target.tag, Pose::Identity());
    for (const auto& t : target.extra_tags) add_tag(tg, t.tag, t.g_ot);
    for (const auto& s : target.shapes) add_shape(tg, s);
    tg.motion = &target.motion;
    target_instances.push_back(int(instances.size() - 1));
    attach_instance(tg, target_instances.back());
  }
  // Moving occluders.
  for (const auto& b : scene.occluders) {
    if (!b.motion || b.shapes.empty()) continue;
    Instance& in = new_instance(b.name);
    for (const auto& s : b.shapes) add_shape(in, s);
    in.motion = &*b.motion;
    attach_instance(in, int(instances.size() - 1));
  }
  check("scene construction");
}

void Renderer::Impl::add_mesh(Instance& in, const Mesh& mesh, GeomInfo info) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
      g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
  auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
  if (!v || !ix) {
    rtcReleaseGeometry(g);
    check("geometry buffer");
    throw std::runtime_error("Embree could not allocate a geometry buffer");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) v[3 * i + size_t(k)] = mesh.vertices[i][k];
    in.box.extend(mesh.vertices[i].cast<double>());
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.triangles[i][size_t(k)] >= mesh.vertices.size()) {
        rtcReleaseGeometry(g);
        throw std::invalid_argument("mesh '" + in.name + "': triangle index out of range");
      }
      ix[3 * i + size_t(k)] = mesh.triangles[i][size_t(k)];
    }
  }
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(in.scene, g);
  rtcReleaseGeometry(g);
  if (id != in.geoms.size()) throw std::runtime_error("unexpected Embree geometry id");
  in.geoms.push_back(std::move(info));
}

void Renderer::Impl::add_shape(Instance& in, const Shape& s) {
  GeomInfo info;
  info.material = s.material;
  info.to_local = s.pose.inverse();
  add_mesh(in, transformed(shape_mesh(s), s.pose), info);
}

void Renderer::Impl::add_tag(Instance& in, const TagSpec& spec, const Pose& g_ot) {
  tags.push_back(std::make_unique<TagTexture>(spec));
  const TagTexture* tex = tags.back().get();
  GeomInfo info;
  info.tag = tex;
  info.to_local = g_ot.inverse();
  add_mesh(in, transformed(tex->card_mesh(), g_ot), info);
}

Instance& Renderer::Impl::new_instance(const std::string& name) {
  instances.emplace_back();
  Instance& in = instances.back();
  in.name = name;
  in.scene = rtcNewScene(device);
  return in;
}

void Renderer::Impl::attach_instance(Instance& in, int index) {
  rtcSetSceneBuildQuality(in.scene, RTC_BUILD_QUALITY_HIGH);
  rtcCommitScene(in.scene);
  in.geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(in.geom, in.scene);
  if (blurred(in)) {  // motion blur: transforms at the motion steps (set_motion)
    rtcSetGeometryTimeStepCount(in.geom, unsigned(motion_steps));
    set_motion(in, *in.motion, 0.0);
  } else {
    rtcSetGeometryTimeStepCount(in.geom, 1);
    set_transform(in, Pose::Identity());
  }
  in.top_id = rtcAttachGeometry(top, in.geom);
  if (instance_of_top_id.size() <= in.top_id) instance_of_top_id.resize(in.top_id + 1, -1);
  instance_of_top_id[in.top_id] = index;
}

void Renderer::Impl::set_transform(Instance& in, const Pose& g) {
  in.g_wb = g;
  in.g_bw = g.inverse();
  float m[12];
  const Eigen::Matrix<double, 3, 4> M = g.matrix().topRows<3>();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) m[3 * c + r] = float(M(r, c));
  rtcSetGeometryTransform(in.geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m);
  rtcCommitGeometry(in.geom);
}

void Renderer::Impl::set_motion(Instance& in, const Trajectory& motion, double t) {
  in.g_wb = motion.at(t);
  in.g_bw = in.g_wb.inverse();
  in.steps.clear();
  for (int k = 0; k < motion_steps; ++k) {
    const double tk = t + (2.0 * k / (motion_steps - 1) - 1.0) * half_window;
    const Eigen::Matrix<float, 3, 4> M = motion.at(tk).matrix().topRows<3>().cast<float>();
    in.steps.push_back(M);
    float m[12];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 3; ++r) m[3 * c + r] = M(r, c);
    rtcSetGeometryTransform(in.geom, unsigned(k), RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m);
  }
  rtcCommitGeometry(in.geom);
}

}  // namespace netvmo::render
