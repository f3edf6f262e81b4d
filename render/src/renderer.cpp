#include "netvmo/render/renderer.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <shared_mutex>
#include <stdexcept>
#include <thread>

namespace netvmo::render {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Packet width of the primary and shadow ray queries (Embree ray packets). 16 is native on
// AVX-512 and emulated with two 8-wide traversals on AVX2 (README, renderer benchmark).
constexpr int K = 16;
using RayHitK = RTCRayHit16;
using RayK = RTCRay16;
inline void intersectK(const int* valid, RTCScene s, RTCIntersectContext* c, RayHitK* r) {
  rtcIntersect16(valid, s, c, r);
}
inline void occludedK(const int* valid, RTCScene s, RTCIntersectContext* c, RayK* r) {
  rtcOccluded16(valid, s, c, r);
}

std::uint64_t splitmix64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Small deterministic Gaussian generator (Box-Muller on splitmix64), identical on every platform
// (std::normal_distribution is not specified bit-exactly).
class Gauss {
 public:
  explicit Gauss(std::uint64_t seed) : s_(seed) {}
  double operator()() {
    if (has_) {
      has_ = false;
      return spare_;
    }
    const double u1 = (double(splitmix64(s_) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    const double u2 = double(splitmix64(s_) >> 11) * (1.0 / 9007199254740992.0);
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2 * M_PI * u2);
    has_ = true;
    return r * std::cos(2 * M_PI * u2);
  }

 private:
  std::uint64_t s_;
  double spare_ = 0;
  bool has_ = false;
};

std::uint64_t tile_seed(std::uint64_t seed, int camera_id, int frame, int tile) {
  std::uint64_t s = seed;
  std::uint64_t h = splitmix64(s);
  s = h ^ (std::uint64_t(std::uint32_t(camera_id)) << 32 | std::uint32_t(frame));
  h = splitmix64(s);
  s = h ^ std::uint64_t(std::uint32_t(tile));
  return splitmix64(s);
}

double radical_inverse2(unsigned i) {
  double r = 0, f = 0.5;
  while (i) {
    if (i & 1) r += f;
    i >>= 1;
    f *= 0.5;
  }
  return r;
}

// Sample offsets relative to the pixel centre, in [-0.5, 0.5)^2.
std::vector<Eigen::Vector2f> sample_offsets(int spp) {
  std::vector<Eigen::Vector2f> out;
  const int n = int(std::lround(std::sqrt(double(spp))));
  if (n * n == spp) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        out.emplace_back(float((i + 0.5) / n - 0.5), float((j + 0.5) / n - 0.5));
  } else {
    for (int i = 0; i < spp; ++i)
      out.emplace_back(float((i + 0.5) / spp - 0.5), float(radical_inverse2(unsigned(i)) + 0.5 / spp - 0.5));
  }
  return out;
}

struct GeomInfo {
  Material material;
  const TagTexture* tag = nullptr;  // non-null: tag quad, `to_local` maps to the tag frame
  Pose to_local = Pose::Identity(); // parent (instance) frame -> shape frame
};

struct Instance {
  std::string name;
  RTCScene scene = nullptr;
  RTCGeometry geom = nullptr;
  unsigned top_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<GeomInfo> geoms;
  const Trajectory* motion = nullptr;  // null: static (identity)
  Pose g_wb = Pose::Identity();        // current pose
  Pose g_bw = Pose::Identity();
};

// The noise-free radiance of a camera's last image and the poses of every instance it was
// rendered with: when nothing has moved, the next frame reuses it and only draws new noise.
struct RadianceCache {
  std::mutex mutex;
  std::vector<Eigen::Matrix4d> key;  // g_wb of every instance
  std::vector<float> acc;            // per pixel, summed over samples (before the sensor)
  bool valid = false;
};

struct CameraCache {
  // Undistorted normalized coordinates per (pixel, sample) when the camera has distortion.
  std::vector<float> table;
  // Bounding box of the undistorted normalized coordinates of the image border.
  double xmin = 0, xmax = 0, ymin = 0, ymax = 0;
};

std::string device_error_text(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE: return "none";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

}  // namespace

struct Renderer::Impl {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::vector<Instance> instances;           // [0] static (if any), then target, moving bodies
  std::vector<int> instance_of_top_id;
  std::vector<std::unique_ptr<TagTexture>> tags;
  std::vector<Eigen::Vector2f> offsets;
  std::vector<CameraCache> cams;
  std::vector<std::unique_ptr<RadianceCache>> radiance;  // per camera
  std::shared_mutex mutex;
  int current_frame = -1;
  int target_instance = -1;

  ~Impl() {
    for (auto& in : instances) {
      if (in.geom) rtcReleaseGeometry(in.geom);
      if (in.scene) rtcReleaseScene(in.scene);
    }
    if (top) rtcReleaseScene(top);
    if (device) rtcReleaseDevice(device);
  }

  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
      throw std::runtime_error(std::string("Embree error in ") + what + ": " + device_error_text(e));
  }

  void add_mesh(Instance& in, const Mesh& mesh, GeomInfo info) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.vertices.size()));
    auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), mesh.triangles.size()));
    if (!v || !ix) {
      rtcReleaseGeometry(g);
      check("geometry buffer");
      throw std::runtime_error("Embree could not allocate a geometry buffer");
    }
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
      for (int k = 0; k < 3; ++k) v[3 * i + size_t(k)] = mesh.vertices[i][k];
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

  void add_shape(Instance& in, const Shape& s) {
    Mesh m;
    switch (s.kind) {
      case Shape::Kind::Box:
        m = make_box(s.size);
        break;
      case Shape::Kind::Plane:
        m = make_plane(s.size.x(), s.size.y());
        break;
      case Shape::Kind::Cylinder:
        m = make_cylinder(s.size.x(), s.size.z(), s.segments);
        break;
      case Shape::Kind::Mesh:
        m = s.mesh;
        break;
    }
    GeomInfo info;
    info.material = s.material;
    info.to_local = s.pose.inverse();
    add_mesh(in, transformed(m, s.pose), info);
  }

  void add_tag(Instance& in, const TagSpec& spec, const Pose& g_ot) {
    tags.push_back(std::make_unique<TagTexture>(spec));
    const TagTexture* tex = tags.back().get();
    const double side = tex->printed_side();
    GeomInfo info;
    info.tag = tex;
    info.to_local = g_ot.inverse();
    add_mesh(in, transformed(make_plane(side, side), g_ot), info);
  }

  Instance& new_instance(const std::string& name) {
    instances.emplace_back();
    Instance& in = instances.back();
    in.name = name;
    in.scene = rtcNewScene(device);
    return in;
  }

  void attach_instance(Instance& in, int index) {
    rtcSetSceneBuildQuality(in.scene, RTC_BUILD_QUALITY_HIGH);
    rtcCommitScene(in.scene);
    in.geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(in.geom, in.scene);
    rtcSetGeometryTimeStepCount(in.geom, 1);
    set_transform(in, Pose::Identity());
    in.top_id = rtcAttachGeometry(top, in.geom);
    if (instance_of_top_id.size() <= in.top_id) instance_of_top_id.resize(in.top_id + 1, -1);
    instance_of_top_id[in.top_id] = index;
  }

  void set_transform(Instance& in, const Pose& g) {
    in.g_wb = g;
    in.g_bw = g.inverse();
    float m[12];
    const Eigen::Matrix<double, 3, 4> M = g.matrix().topRows<3>();
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 3; ++r) m[3 * c + r] = float(M(r, c));
    rtcSetGeometryTransform(in.geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m);
    rtcCommitGeometry(in.geom);
  }
};

void SceneDescription::validate() const {
  if (cameras.empty()) throw std::invalid_argument("the scene has no cameras");
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].id <= 0)
      throw std::invalid_argument("camera ids must be positive integers (got " +
                                  std::to_string(cameras[i].id) + ")");
    for (size_t j = 0; j < i; ++j)
      if (cameras[j].id == cameras[i].id)
        throw std::invalid_argument("duplicate camera id " + std::to_string(cameras[i].id));
    try {
      cameras[i].intrinsics.validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("camera " + std::to_string(cameras[i].id) + ": " + e.what());
    }
  }
  for (const auto& e : edges) {
    auto known = [&](int id) {
      return std::any_of(cameras.begin(), cameras.end(), [&](const CameraSpec& c) { return c.id == id; });
    };
    if (!known(e.first) || !known(e.second) || e.first == e.second)
      throw std::invalid_argument("edge [" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                                  "] must join two different known cameras");
  }
  if (!(fps > 0)) throw std::invalid_argument("fps must be positive");
  if (frames < 1) throw std::invalid_argument("frames must be at least 1");
  if (imaging.spp < 1 || imaging.spp > 1024) throw std::invalid_argument("spp must be between 1 and 1024");
  if (imaging.tile < 1) throw std::invalid_argument("tile must be positive");
  if (imaging.threads < 0) throw std::invalid_argument("threads must be >= 0");
  if (imaging.visibility_grid < 1) throw std::invalid_argument("visibility_grid must be positive");
  if (imaging.read_noise < 0 || imaging.shot_noise < 0)
    throw std::invalid_argument("noise levels must be >= 0");
  target.motion.validate();
  for (const auto& b : occluders)
    if (b.motion) b.motion->validate();
  for (const auto& l : lights)
    if (l.kind == Light::Kind::Directional && l.direction.norm() < 1e-12)
      throw std::invalid_argument("directional light needs a non-zero direction");
}

Renderer::Renderer(SceneDescription scene) : scene_(std::move(scene)), impl_(std::make_unique<Impl>()) {
  scene_.validate();
  Impl& I = *impl_;
  I.device = rtcNewDevice(nullptr);
  if (!I.device) throw std::runtime_error("cannot create the Embree device: " +
                                          device_error_text(rtcGetDeviceError(nullptr)));
  I.top = rtcNewScene(I.device);
  rtcSetSceneFlags(I.top, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(I.top, RTC_BUILD_QUALITY_LOW);
  I.instances.reserve(2 + scene_.occluders.size());

  // Static geometry: one scene, built once, instanced with the identity.
  bool any_static = false;
  for (const auto& b : scene_.occluders) any_static |= !b.motion && !b.shapes.empty();
  if (any_static) {
    Instance& st = I.new_instance("static");
    for (const auto& b : scene_.occluders)
      if (!b.motion)
        for (const auto& s : b.shapes) I.add_shape(st, s);
    I.attach_instance(st, int(I.instances.size() - 1));
  }
  // The target.
  {
    Instance& tg = I.new_instance("target");
    I.add_tag(tg, scene_.target.tag, Pose::Identity());
    for (const auto& t : scene_.target.extra_tags) I.add_tag(tg, t.tag, t.g_ot);
    for (const auto& s : scene_.target.shapes) I.add_shape(tg, s);
    tg.motion = &scene_.target.motion;
    I.target_instance = int(I.instances.size() - 1);
    I.attach_instance(tg, I.target_instance);
  }
  // Moving occluders.
  for (const auto& b : scene_.occluders) {
    if (!b.motion || b.shapes.empty()) continue;
    Instance& in = I.new_instance(b.name);
    for (const auto& s : b.shapes) I.add_shape(in, s);
    in.motion = &*b.motion;
    I.attach_instance(in, int(I.instances.size() - 1));
  }
  I.check("scene construction");

  I.offsets = sample_offsets(scene_.imaging.spp);
  // Per-camera ray tables (distortion inverted once per pixel sample) and FOV bounds.
  I.cams.resize(scene_.cameras.size());
  for (size_t c = 0; c < scene_.cameras.size(); ++c) I.radiance.push_back(std::make_unique<RadianceCache>());
  for (size_t c = 0; c < scene_.cameras.size(); ++c) {
    const Intrinsics& K = scene_.cameras[c].intrinsics;
    CameraCache& cc = I.cams[c];
    cc.xmin = cc.ymin = std::numeric_limits<double>::infinity();
    cc.xmax = cc.ymax = -std::numeric_limits<double>::infinity();
    auto extend = [&](double u, double v) {
      const auto x = K.unproject(Vec2(u, v));
      if (!x) return;
      cc.xmin = std::min(cc.xmin, x->x());
      cc.xmax = std::max(cc.xmax, x->x());
      cc.ymin = std::min(cc.ymin, x->y());
      cc.ymax = std::max(cc.ymax, x->y());
    };
    const double W = K.width - 0.5, H = K.height - 0.5;
    for (int i = 0; i <= 64; ++i) {
      const double a = i / 64.0;
      extend(-0.5 + a * K.width, -0.5);
      extend(-0.5 + a * K.width, H);
      extend(-0.5, -0.5 + a * K.height);
      extend(W, -0.5 + a * K.height);
    }
    if (!K.has_distortion()) continue;
    const size_t spp = I.offsets.size();
    cc.table.resize(size_t(K.width) * size_t(K.height) * spp * 2);
    for (int r = 0; r < K.height; ++r)
      for (int col = 0; col < K.width; ++col)
        for (size_t s = 0; s < spp; ++s) {
          const auto x = K.unproject(Vec2(col + I.offsets[s].x(), r + I.offsets[s].y()));
          const size_t i = ((size_t(r) * size_t(K.width) + size_t(col)) * spp + s) * 2;
          cc.table[i] = x ? float(x->x()) : std::numeric_limits<float>::quiet_NaN();
          cc.table[i + 1] = x ? float(x->y()) : std::numeric_limits<float>::quiet_NaN();
        }
  }
  set_frame(0);
}

Renderer::~Renderer() = default;

int Renderer::camera_index(int id) const {
  for (size_t i = 0; i < scene_.cameras.size(); ++i)
    if (scene_.cameras[i].id == id) return int(i);
  throw std::invalid_argument("unknown camera id " + std::to_string(id));
}

Pose Renderer::target_pose(int frame) const { return scene_.target.motion.at(time_of(frame)); }

void Renderer::set_frame(int frame) {
  std::unique_lock<std::shared_mutex> lock(impl_->mutex);
  Impl& I = *impl_;
  if (I.current_frame == frame) return;
  const double t = time_of(frame);
  for (auto& in : I.instances)
    if (in.motion) I.set_transform(in, in.motion->at(t));
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

cv::Mat Renderer::render(int ci, int frame) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const CameraSpec& cam = scene_.cameras[size_t(ci)];
  const Intrinsics& Kc = cam.intrinsics;
  const CameraCache& cc = I.cams[size_t(ci)];
  const Imaging& im = scene_.imaging;
  const int W = Kc.width, H = Kc.height, T = im.tile;
  const int tiles_x = (W + T - 1) / T, tiles_y = (H + T - 1) / T, ntiles = tiles_x * tiles_y;
  const int spp = int(I.offsets.size());
  cv::Mat out(H, W, CV_8UC1);

  const Eigen::Matrix3f R = cam.g_wi_true.linear().cast<float>();
  const Eigen::Vector3f O = cam.g_wi_true.translation().cast<float>();
  const float fx = float(Kc.fx), fy = float(Kc.fy), cx = float(Kc.cx), cy = float(Kc.cy);
  const bool table = !cc.table.empty();

  struct LightF {
    bool directional, shadows;
    Eigen::Vector3f v;  // directional: unit vector towards the light; point: position
    float intensity;
  };
  std::vector<LightF> lights;
  for (const auto& l : scene_.lights)
    lights.push_back({l.kind == Light::Kind::Directional, l.shadows,
                      l.kind == Light::Kind::Directional
                          ? Eigen::Vector3f((-l.direction.normalized()).cast<float>())
                          : Eigen::Vector3f(l.position.cast<float>()),
                      float(l.intensity)});
  // Per top-level instance id: rotation (object -> world normals), world -> shape transforms.
  const size_t ninst = I.instance_of_top_id.size();
  std::vector<Eigen::Matrix3f> inst_R(ninst, Eigen::Matrix3f::Identity());
  for (size_t t = 0; t < ninst; ++t)
    if (I.instance_of_top_id[t] >= 0)
      inst_R[t] = I.instances[size_t(I.instance_of_top_id[t])].g_wb.linear().cast<float>();

  // Per (instance, geometry): world -> shape frame (texture coordinates) for this frame.
  std::vector<std::vector<Eigen::Affine3f>> to_local(ninst);
  for (size_t t = 0; t < ninst; ++t)
    if (I.instance_of_top_id[t] >= 0) {
      const Instance& in = I.instances[size_t(I.instance_of_top_id[t])];
      for (const auto& g : in.geoms) to_local[t].push_back(Eigen::Affine3f((g.to_local * in.g_bw).cast<float>().matrix()));
    }
  const float ambient = float(im.ambient), background = float(im.background);
  const double scale = 255.0 * im.exposure / spp;

  const int b = std::max(1, int(std::lround(std::sqrt(double(K) / spp))));
  // Static scene since this camera's last image: reuse its radiance, draw new noise only (the
  // output is byte-identical to tracing again).
  RadianceCache& rc = *I.radiance[size_t(ci)];
  std::unique_lock<std::mutex> cache_lock(rc.mutex);
  std::vector<Eigen::Matrix4d> key;
  for (const auto& in : I.instances) key.push_back(in.g_wb.matrix());
  const bool reuse = im.reuse_static && rc.valid && rc.key == key;
  if (!reuse) {
    rc.valid = false;
    rc.acc.assign(size_t(W) * size_t(H), 0.0f);
  }
  std::atomic<int> next{0};
  auto worker = [&]() {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RTCIntersectContext sctx;
    rtcInitIntersectContext(&sctx);
    // Shadow packets stay INCOHERENT: with RTC_INTERSECT_CONTEXT_FLAG_COHERENT, rtcOccluded16 of
    // Debian's Embree 3.13.5 never returned on this machine (AVX-512), whatever the tfar values.
    alignas(64) RayHitK rh;
    alignas(64) RayK sr;
    alignas(64) int valid[K];
    alignas(64) int svalid[K];
    int lane_pix[K];
    float lane_rad[K], lane_alb[K], lane_contrib[K];
    Eigen::Vector3f lane_p[K], lane_n[K];
    std::vector<float> acc(size_t(T * T));
    for (int tile = next++; tile < ntiles; tile = next++) {
      const int tx0 = (tile % tiles_x) * T, ty0 = (tile / tiles_x) * T;
      const int tw = std::min(T, W - tx0), th = std::min(T, H - ty0);
      // Packets cover b x b pixel blocks with all their samples (b*b*spp ~ K), so each packet's
      // rays form a narrow, square frustum (coherent primary and shadow rays).
      const int bxn = (tw + b - 1) / b, byn = (th + b - 1) / b, per_block = b * b * spp;
      const int nsamples = bxn * byn * per_block;
      std::fill(acc.begin(), acc.end(), 0.0f);
      if (reuse) {
        for (int y = 0; y < th; ++y)
          for (int x = 0; x < tw; ++x) acc[size_t(y * tw + x)] = rc.acc[size_t(ty0 + y) * size_t(W) + size_t(tx0 + x)];
      }
      for (int base = reuse ? nsamples : 0; base < nsamples; base += K) {
        // Primary rays: one packet of K samples (consecutive samples of neighbouring pixels).
        for (int j = 0; j < K; ++j) {
          const int idx = base + j;
          valid[j] = 0;
          lane_pix[j] = -1;
          lane_rad[j] = 0;
          rh.ray.org_x[j] = O.x();
          rh.ray.org_y[j] = O.y();
          rh.ray.org_z[j] = O.z();
          rh.ray.dir_x[j] = 0;
          rh.ray.dir_y[j] = 0;
          rh.ray.dir_z[j] = 1;
          rh.ray.tnear[j] = 0;
          rh.ray.tfar[j] = kInf;
          rh.ray.time[j] = 0;
          rh.ray.mask[j] = 0xFFFFFFFFu;
          rh.ray.id[j] = unsigned(j);
          rh.ray.flags[j] = 0;
          rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
          if (idx >= nsamples) continue;
          const int blk = idx / per_block, w = idx % per_block, pib = w / spp, s = w % spp;
          const int cin = (blk % bxn) * b + pib % b, rin = (blk / bxn) * b + pib / b;
          if (cin >= tw || rin >= th) continue;  // block overhangs a partial tile
          const int p = rin * tw + cin;
          const int col = tx0 + cin, row = ty0 + rin;
          lane_pix[j] = p;
          float xn, yn;
          if (table) {
            const size_t ti = ((size_t(row) * size_t(W) + size_t(col)) * size_t(spp) + size_t(s)) * 2;
            xn = cc.table[ti];
            yn = cc.table[ti + 1];
            if (!std::isfinite(xn)) continue;  // outside the invertible region: black
          } else {
            xn = (float(col) + I.offsets[size_t(s)].x() - cx) / fx;
            yn = (float(row) + I.offsets[size_t(s)].y() - cy) / fy;
          }
          const Eigen::Vector3f d = R * Eigen::Vector3f(xn, yn, 1.0f);
          rh.ray.dir_x[j] = d.x();
          rh.ray.dir_y[j] = d.y();
          rh.ray.dir_z[j] = d.z();
          valid[j] = -1;
        }
        intersectK(valid, I.top, &ctx, &rh);
        // Surface points: position, normal facing the camera, albedo from the texture.
        for (int j = 0; j < K; ++j) {
          if (!valid[j]) continue;
          if (rh.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID) {
            lane_rad[j] = background;
            valid[j] = 0;
            continue;
          }
          const unsigned top_id = rh.hit.instID[0][j];
          const GeomInfo& gi = I.instances[size_t(I.instance_of_top_id[top_id])].geoms[rh.hit.geomID[j]];
          const Eigen::Vector3f D(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]);
          const Eigen::Vector3f P = O + rh.ray.tfar[j] * D;
          Eigen::Vector3f n =
              inst_R[top_id] * Eigen::Vector3f(rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]);
          if (n.dot(D) > 0) n = -n;
          n.normalize();
          const Eigen::Affine3f& wl = to_local[top_id][rh.hit.geomID[j]];
          const Eigen::Vector3f pl = wl * P;
          lane_alb[j] = float(gi.tag ? gi.tag->albedo(pl.x(), pl.y())
                                     : gi.material.eval(pl.cast<double>(), (wl.linear() * n).cast<double>()));
          lane_p[j] = P;
          lane_n[j] = n;
          lane_rad[j] = lane_alb[j] * ambient;
        }
        // Direct light, with one shadow-ray packet per light.
        for (const LightF& L : lights) {
          bool any = false;
          for (int j = 0; j < K; ++j) {
            svalid[j] = 0;
            sr.org_x[j] = sr.org_y[j] = sr.org_z[j] = 0;
            sr.dir_x[j] = sr.dir_y[j] = 0;
            sr.dir_z[j] = 1;
            sr.tnear[j] = 0;
            sr.tfar[j] = 0;
            sr.time[j] = 0;
            sr.mask[j] = 0xFFFFFFFFu;
            sr.id[j] = unsigned(j);
            sr.flags[j] = 0;
            lane_contrib[j] = 0;
            if (!valid[j]) continue;
            Eigen::Vector3f l;
            float e, tfar;
            if (L.directional) {
              l = L.v;
              e = L.intensity;
              tfar = kInf;
            } else {
              l = L.v - lane_p[j];
              const float d2 = std::max(l.squaredNorm(), 1e-6f), d = std::sqrt(d2);
              e = L.intensity / d2;
              l /= d;
              tfar = d - 1e-3f;
            }
            const float c = lane_n[j].dot(l);
            if (c <= 0) continue;
            lane_contrib[j] = lane_alb[j] * e * c;
            if (!L.shadows) {
              lane_rad[j] += lane_contrib[j];
              continue;
            }
            const Eigen::Vector3f o = lane_p[j] + 2e-4f * lane_n[j];
            sr.org_x[j] = o.x();
            sr.org_y[j] = o.y();
            sr.org_z[j] = o.z();
            sr.dir_x[j] = l.x();
            sr.dir_y[j] = l.y();
            sr.dir_z[j] = l.z();
            sr.tfar[j] = tfar;
            svalid[j] = -1;
            any = true;
          }
          if (!any) continue;
          occludedK(svalid, I.top, &sctx, &sr);
          for (int j = 0; j < K; ++j)
            if (svalid[j] && sr.tfar[j] >= 0) lane_rad[j] += lane_contrib[j];  // tfar = -inf if blocked
        }
        for (int j = 0; j < K; ++j)
          if (lane_pix[j] >= 0) acc[size_t(lane_pix[j])] += lane_rad[j];
      }
      if (!reuse) {
        for (int y = 0; y < th; ++y)
          for (int x = 0; x < tw; ++x) rc.acc[size_t(ty0 + y) * size_t(W) + size_t(tx0 + x)] = acc[size_t(y * tw + x)];
      }
      // Sensor: mean radiance -> DN, plus read and shot noise from the tile's own generator.
      Gauss gauss(tile_seed(im.seed, cam.id, frame, tile));
      for (int y = 0; y < th; ++y) {
        auto* row = out.ptr<std::uint8_t>(ty0 + y);
        for (int x = 0; x < tw; ++x) {
          double dn = scale * acc[size_t(y * tw + x)];
          if (im.noise) {
            const double var = im.read_noise * im.read_noise + im.shot_noise * std::max(dn, 0.0);
            dn += std::sqrt(var) * gauss();
          }
          row[tx0 + x] = std::uint8_t(std::clamp(std::lround(dn), 0L, 255L));
        }
      }
    }
  };
  const int nthreads = std::max(1, std::min(ntiles, im.threads > 0 ? im.threads
                                                   : int(std::max(1u, std::thread::hardware_concurrency()))));
  std::vector<std::thread> pool;
  for (int t = 1; t < nthreads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (!reuse) {
    rc.key = std::move(key);
    rc.valid = true;
  }
  return out;
}

FrameTruth Renderer::truth(int ci, int frame) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const CameraSpec& cam = scene_.cameras[size_t(ci)];
  const Intrinsics& Kc = cam.intrinsics;
  const CameraCache& cc = I.cams[size_t(ci)];
  FrameTruth t;
  t.frame = frame;
  t.t = time_of(frame);
  t.camera_id = cam.id;
  t.g_wo = I.instances[size_t(I.target_instance)].g_wb;
  t.g_io = cam.g_wi_true.inverse() * t.g_wo;
  const double h = scene_.target.tag.size / 2;

  // A camera-frame point is in the field of view if it is in front, its undistorted normalized
  // coordinates lie within those of the image border (guards against the distortion polynomial
  // folding far-away points back into the image) and its distorted pixel lies in the image.
  auto in_fov = [&](const Vec3& pc, std::optional<Vec2>* uv_out) {
    const auto uv = Kc.project(pc);
    if (uv_out) *uv_out = uv;
    if (!uv) return false;
    const double xn = pc.x() / pc.z(), yn = pc.y() / pc.z();
    const double mx = 0.02 * (cc.xmax - cc.xmin), my = 0.02 * (cc.ymax - cc.ymin);
    if (xn < cc.xmin - mx || xn > cc.xmax + mx || yn < cc.ymin - my || yn > cc.ymax + my) return false;
    return uv->x() >= -0.5 && uv->x() <= Kc.width - 0.5 && uv->y() >= -0.5 && uv->y() <= Kc.height - 0.5;
  };

  const Vec3 corners_o[4] = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  t.in_fov = true;
  for (int k = 0; k < 4; ++k) {
    const Vec3 pc = t.g_io * corners_o[k];
    std::optional<Vec2> uv;
    const bool inside = in_fov(pc, &uv);
    t.corners[size_t(k)] = uv;
    t.in_fov = t.in_fov && inside;
  }

  // Visible fraction: grid over the printed tag (the black square and its white quiet zone,
  // which the detector needs too), each sample front-facing, in view and with an unobstructed
  // line of sight from the camera centre.
  const int n = scene_.imaging.visibility_grid;
  const double hp = 0.5 * impl_->tags.front()->printed_side();
  const Vec3 cam_w = cam.g_wi_true.translation();
  const Vec3 normal_w = t.g_wo.linear().col(2);
  int seen = 0;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const Vec3 po(-hp + (2 * hp) * (a + 0.5) / n, -hp + (2 * hp) * (b + 0.5) / n, 0);
      const Vec3 pw = t.g_wo * po;
      const Vec3 to_cam = cam_w - pw;
      if (normal_w.dot(to_cam) <= 0) continue;
      if (!in_fov(t.g_io * po, nullptr)) continue;
      const double dist = to_cam.norm();
      const Vec3 d = -to_cam / dist;
      RTCRay ray;
      ray.org_x = float(cam_w.x());
      ray.org_y = float(cam_w.y());
      ray.org_z = float(cam_w.z());
      ray.dir_x = float(d.x());
      ray.dir_y = float(d.y());
      ray.dir_z = float(d.z());
      ray.tnear = 0;
      ray.tfar = float(dist - std::max(1e-4, 1e-5 * dist));
      ray.time = 0;
      ray.mask = 0xFFFFFFFFu;
      ray.id = 0;
      ray.flags = 0;
      rtcOccluded1(I.top, &ctx, &ray);
      if (ray.tfar >= 0) ++seen;
    }
  t.visible_fraction = double(seen) / double(n * n);
  return t;
}

std::uint64_t Renderer::intersect_bare(int ci, int frame, int threads) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const CameraSpec& cam = scene_.cameras[size_t(ci)];
  const Intrinsics& Kc = cam.intrinsics;
  const CameraCache& cc = I.cams[size_t(ci)];
  const int W = Kc.width, H = Kc.height, spp = int(I.offsets.size());
  const Eigen::Matrix3f R = cam.g_wi_true.linear().cast<float>();
  const Eigen::Vector3f O = cam.g_wi_true.translation().cast<float>();
  std::atomic<int> next_row{0};
  std::atomic<std::uint64_t> hits{0};
  auto worker = [&]() {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    std::uint64_t local = 0;
    for (int row = next_row++; row < H; row = next_row++)
      for (int col = 0; col < W; ++col)
        for (int s = 0; s < spp; ++s) {
          float xn, yn;
          if (!cc.table.empty()) {
            const size_t ti = ((size_t(row) * size_t(W) + size_t(col)) * size_t(spp) + size_t(s)) * 2;
            xn = cc.table[ti];
            yn = cc.table[ti + 1];
          } else {
            xn = float((col + I.offsets[size_t(s)].x() - Kc.cx) / Kc.fx);
            yn = float((row + I.offsets[size_t(s)].y() - Kc.cy) / Kc.fy);
          }
          const Eigen::Vector3f d = R * Eigen::Vector3f(xn, yn, 1.0f);
          RTCRayHit r;
          r.ray.org_x = O.x();
          r.ray.org_y = O.y();
          r.ray.org_z = O.z();
          r.ray.dir_x = d.x();
          r.ray.dir_y = d.y();
          r.ray.dir_z = d.z();
          r.ray.tnear = 0;
          r.ray.tfar = kInf;
          r.ray.time = 0;
          r.ray.mask = 0xFFFFFFFFu;
          r.ray.id = 0;
          r.ray.flags = 0;
          r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(I.top, &ctx, &r);
          local += r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
    hits += local;
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return hits;
}

}  // namespace netvmo::render
