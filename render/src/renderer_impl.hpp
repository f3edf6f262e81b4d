// Private to render/src: the renderer's state (Renderer::Impl) and what its source files share.
//
//   renderer.cpp        Renderer's construction and frame state (set_frame, acquire)
//   scene_validate.cpp  SceneDescription::validate
//   scene_build.cpp     the Embree device, meshes, instances and commits
//   camera_rays.cpp     sample offsets, per-camera inverse-distortion ray tables, FOV bounds
//   shading.cpp         the shading kernel: radiance of a traced packet (textures, lights, shadows)
//   sensor.cpp          radiance -> 8-bit pixels with seeded read and shot noise
//   render_loop.cpp     Renderer::render: frame -> tiles -> packets
//   reuse_bounds.cpp    which packets a moved body or its shadow can touch (radiance reuse)
//   ground_truth.cpp    Renderer::truth: corners, field of view, visible fraction
//   intersect_bare.cpp  Renderer::intersect_bare, the benchmark baseline
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <thread>
#include <vector>

#include "netvmo/render/renderer.hpp"

namespace netvmo::render {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Packet width of the primary and shadow ray queries (Embree ray packets). 16 is native on
// AVX-512 and emulated with two 8-wide traversals on AVX2 (docs/benchmarks.md, "Renderer").
constexpr int kPacket = 16;
using RayHitK = RTCRayHit16;
using RayK = RTCRay16;
inline void intersectK(const int* valid, RTCScene s, RTCIntersectContext* c, RayHitK* r) {
  rtcIntersect16(valid, s, c, r);
}
inline void occludedK(const int* valid, RTCScene s, RTCIntersectContext* c, RayK* r) {
  rtcOccluded16(valid, s, c, r);
}

struct GeomInfo {
  Material material;
  const TagTexture* tag = nullptr;   // non-null: tag quad, `to_local` maps to the tag frame
  Pose to_local = Pose::Identity();  // parent (instance) frame -> shape frame
};

struct Instance {
  std::string name;
  RTCScene scene = nullptr;
  RTCGeometry geom = nullptr;
  unsigned top_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<GeomInfo> geoms;
  const Trajectory* motion = nullptr;  // null: static (identity)
  Eigen::AlignedBox3d box;             // bounds of the geometry in the instance frame
  Pose g_wb = Pose::Identity();        // current pose (at the frame's time)
  Pose g_bw = Pose::Identity();
  // Motion blur (Renderer::Impl::motion_steps > 1, a moving instance): g_wb at the motion steps
  // over the frame's exposure window, as Embree interpolates them (3 x 4, linearly).
  std::vector<Eigen::Matrix<float, 3, 4>> steps;
};

/// What a traced packet covered: the bounds of its rays in the camera's undistorted normalized
/// coordinates and of the surface points they hit (lo > hi: none).
struct PacketBounds {
  float xmin = kInf, xmax = -kInf, ymin = kInf, ymax = -kInf;
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(kInf);
  Eigen::Vector3f hi = Eigen::Vector3f::Constant(-kInf);
  bool no_hit() const { return !(lo.x() <= hi.x()); }
  bool no_ray() const { return !(xmin <= xmax); }
};

// The noise-free radiance of a camera's last image, the poses of every instance and of the
// camera it was rendered with and where each packet's primary rays hit: the next frame reuses
// the radiance of every packet that no moved body or its shadow can touch (all of them when
// nothing has moved) and draws new noise. A camera that moved re-traces its whole image.
struct RadianceCache {
  std::mutex mutex;
  std::vector<Eigen::Matrix4d> key;                      // g_wb of every instance
  Eigen::Matrix4d camera = Eigen::Matrix4d::Identity();  // g_wc the image was rendered from
  std::vector<float> acc;             // per pixel, summed over samples (before the sensor)
  std::vector<PacketBounds> packets;  // per packet, in tile order
  double traced_fraction = 1;         // of the packets, in the last image
  bool valid = false;
};

struct CameraCache {
  // Undistorted normalized coordinates per (pixel, sample) when the camera has distortion.
  std::vector<float> table;
  // Imaging::Sampling::Jittered without distortion: each pixel's shift of the sample pattern
  // (pixel_shift()), row-major; empty otherwise (the table holds the shifted samples already).
  std::vector<Eigen::Vector2f> shift;
  int width = 0, height = 0, spp = 0;    // the image's size, samples per pixel
  float fx = 1, fy = 1, cx = 0, cy = 0;  // the pinhole in the kernel's single precision
  // Bounding box of the undistorted normalized coordinates of the image border.
  double xmin = 0, xmax = 0, ymin = 0, ymax = 0;
};

struct Renderer::Impl {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::vector<Instance> instances;  // [0] static (if any), then the targets, moving bodies
  std::vector<int> instance_of_top_id;
  std::vector<std::unique_ptr<TagTexture>> tags;
  std::vector<Eigen::Vector2f> offsets;
  std::vector<CameraCache> cams;
  std::vector<std::unique_ptr<RadianceCache>> radiance;  // per camera
  std::shared_mutex mutex;
  int current_frame = -1;
  std::vector<int> target_instances;  // instance of each target
  // Motion blur and rolling shutter (SensorModel::time_effects() of any camera): moving
  // instances carry `motion_steps` transforms spread evenly over [t - half_window, t +
  // half_window] around the frame's time t (Embree ray time 0..1, the frame's time at 0.5);
  // 1: one transform at t, the clean renderer.
  int motion_steps = 1;
  double half_window = 0;  // [s]: the largest exposure half-time plus rolling-shutter offset

  ~Impl();

  // Scene building (scene_build.cpp). build() creates the device and commits every instance:
  // the static geometry in one scene built once, the target and the moving occluders.
  void build(const SceneDescription& scene);
  void check(const char* what) const;
  void set_transform(Instance& in, const Pose& g);
  /// Whether the instance is motion-blurred: it moves and motion_steps > 1.
  bool blurred(const Instance& in) const {
    return motion_steps > 1 && in.motion && in.motion->kind != Trajectory::Kind::Static;
  }
  /// Motion blur: the instance's pose at every motion step of the window around time t.
  void set_motion(Instance& in, const Trajectory& motion, double t);

 private:
  void create_device();
  void add_mesh(Instance& in, const Mesh& mesh, GeomInfo info);
  void add_shape(Instance& in, const Shape& s);
  void add_tag(Instance& in, const TagSpec& spec, const Pose& g_ot);
  Instance& new_instance(const std::string& name);
  void attach_instance(Instance& in, int index);
};

// Camera rays (camera_rays.cpp).
/// Sample offsets relative to the pixel centre, in [-0.5, 0.5)^2.
std::vector<Eigen::Vector2f> sample_offsets(int spp);
/// Imaging::Sampling::Jittered: the key of a camera's pixel shifts (the scene's seed and the
/// camera's id); 0 for Imaging::Sampling::Grid, whose pixels are not shifted.
std::uint64_t pixel_jitter_key(const Imaging& im, int camera_id);
/// The rays of a camera, built once: FOV bounds; with distortion, the undistorted ray of every
/// (pixel, sample); without, with a non-zero `jitter_key`, every pixel's shift.
CameraCache make_camera_cache(const Intrinsics& Kc, const std::vector<Eigen::Vector2f>& offsets,
                              std::uint64_t jitter_key);
/// splitmix64's finalizer: a well-mixed 64-bit hash of z.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
/// Index of (row, col, sample) in CameraCache::table.
inline size_t ray_table_index(int row, int col, int sample, int width, int spp) {
  return ((size_t(row) * size_t(width) + size_t(col)) * size_t(spp) + size_t(sample)) * 2;
}
/// Sample offset `o` (in [-0.5, 0.5)^2) moved by `shift` (in [0, 1)^2) toroidally within its
/// pixel: the pattern keeps one sample per stratum.
inline Eigen::Vector2f shifted_sample(const Eigen::Vector2f& o, const Eigen::Vector2f& shift) {
  auto wrap = [](float v) {  // v + 0.5 taken into [0, 1), back to [-0.5, 0.5)
    v += 0.5f;
    v -= std::floor(v);
    return v - 0.5f;
  };
  return {wrap(o.x() + shift.x()), wrap(o.y() + shift.y())};
}
/// The primary ray of sample s of pixel (col, row), in undistorted normalized coordinates
/// (xn, yn): from the camera's ray table with distortion, false where the model cannot be
/// inverted (the sample stays black); else through the pinhole, the pattern's offset moved by
/// the pixel's shift when the sampling is jittered. Rendering and the bare intersection
/// benchmark both take their rays here.
inline bool primary_ray(const CameraCache& cc, const std::vector<Eigen::Vector2f>& offsets, int col,
                        int row, int s, float& xn, float& yn) {
  if (!cc.table.empty()) {
    const size_t ti = ray_table_index(row, col, s, cc.width, cc.spp);
    xn = cc.table[ti];
    yn = cc.table[ti + 1];
    return std::isfinite(xn);
  }
  Eigen::Vector2f o = offsets[size_t(s)];
  if (!cc.shift.empty())
    o = shifted_sample(o, cc.shift[size_t(row) * size_t(cc.width) + size_t(col)]);
  xn = (float(col) + o.x() - cc.cx) / cc.fx;
  yn = (float(row) + o.y() - cc.cy) / cc.fy;
  return true;
}

// The shading kernel (shading.cpp).
/// A light in the kernel's single precision.
struct LightF {
  bool directional, shadows;
  Eigen::Vector3f v;  // directional: unit vector towards the light; point: position
  float intensity;
};

/// What the kernel needs of the current frame.
struct Shading {
  const Renderer::Impl* impl = nullptr;
  std::vector<LightF> lights;
  std::vector<Eigen::Matrix3f> inst_R;                 // per top-level id: object -> world normals
  std::vector<std::vector<Eigen::Affine3f>> to_local;  // per (top id, geometry): world -> shape
  float ambient = 0, background = 0;
  // Motion blur: per top id, the instance's motion steps (empty: static) and per geometry its
  // instance -> shape transform; the shading of a hit interpolates the instance at the ray time.
  std::vector<std::vector<Eigen::Matrix<float, 3, 4>>> steps;
  std::vector<std::vector<Eigen::Affine3f>> geom_local;
};
Shading make_shading(const Renderer::Impl& impl, const SceneDescription& scene);

/// One packet of kPacket samples and its per-lane shading state.
struct Packet {
  alignas(64) RayHitK rh;
  alignas(64) RayK sr;
  alignas(64) int valid[kPacket];
  alignas(64) int svalid[kPacket];
  int pix[kPacket];  // pixel of the lane in its tile, -1: none
  float rad[kPacket], alb[kPacket], contrib[kPacket];
  float gloss[kPacket], shininess[kPacket];  // specular term of a glossy tag print (0: matte)
  Eigen::Vector3f p[kPacket], n[kPacket];
};

/// Radiance of every lane of a traced primary packet (each lane from its own ray origin):
/// background, textured albedo times ambient plus each light, one shadow-ray packet per light
/// (context `sctx`).
void shade_packet(const Shading& sh, Packet& pk, RTCIntersectContext* sctx);

// Radiance reuse under motion (reuse_bounds.cpp).
/// A body that moved since a camera's cached image: a world box holding it at both poses
/// (padded), and that box's bounds in the camera's undistorted normalized coordinates.
/// Also, for testing single primary rays, its own box (padded) and, at each of the two poses,
/// the camera centre and camera -> body rotation in the body frame.
struct MovedBody {
  Eigen::AlignedBox3d box;
  bool everywhere = false;  // the box reaches the camera plane: any primary ray may hit it
  bool behind = false;      // the box lies behind the camera: no primary ray hits it
  float xmin = 0, xmax = 0, ymin = 0, ymax = 0;
  Eigen::AlignedBox3d local;
  Eigen::Vector3d origin[2];
  Eigen::Matrix3d rotation[2];
};
/// The instances whose pose differs between `cached` and now (their g_wb), seen from g_wc.
std::vector<MovedBody> moved_bodies(const Renderer::Impl& impl,
                                    const std::vector<Eigen::Matrix4d>& cached, const Pose& g_wc);
/// Whether one of the packet's primary rays may hit the body.
inline bool primary_may_hit(const MovedBody& b, const PacketBounds& p) {
  if (p.no_ray() || b.behind) return false;
  return b.everywhere ||
         (p.xmax >= b.xmin && p.xmin <= b.xmax && p.ymax >= b.ymin && p.ymin <= b.ymax);
}
/// Whether the primary ray through normalized coordinates (xn, yn) may hit the body's own box
/// at either pose.
bool ray_may_hit(const MovedBody& b, float xn, float yn);
/// Whether a shadow ray from a point the packet hit towards L may hit the body (false without
/// shadows).
bool shadow_may_hit(const MovedBody& b, const LightF& L, const PacketBounds& p);

// The sensor (sensor.cpp).
/// Number of motion steps over a frame's exposure window with motion blur.
constexpr int kMotionSteps = 9;
/// Motion-blur window of a scene: the largest half exposure plus rolling-shutter offset of its
/// cameras [s] (0: no camera has time effects).
double motion_half_window(const SceneDescription& scene);

/// Seed of a tile's noise generator, from (seed, camera id, frame, tile).
std::uint64_t tile_seed(std::uint64_t seed, int camera_id, int frame, int tile);
/// Writes a tile's pixels at (x0, y0) of `out`: DN = scale * acc, plus read and shot noise
/// drawn from the generator seeded with `seed` when im.noise, rounded and clamped to [0, 255].
void expose_tile(const Imaging& im, double scale, std::uint64_t seed, const std::vector<float>& acc,
                 int x0, int y0, int w, int h, cv::Mat& out);

/// The realistic sensor (SensorModel::image_effects()): the whole image's summed radiance `acc`
/// (row-major, `scale` * acc = the linear signal S [DN]) -> vignetting -> Gaussian PSF -> full
/// well and bloom -> read and shot noise (tile by tile, from tile_seed(seed, camera id, frame,
/// tile) as expose_tile) -> gain -> tone curve -> 8 bits in `out`.
void develop_image(const SensorModel& sm, const Imaging& im, const Intrinsics& K, double scale,
                   int camera_id, int frame, const std::vector<float>& acc, cv::Mat& out);

/// Runs `worker` on `nthreads` threads (the calling one included) and joins them.
template <class Worker>
void run_threads(int nthreads, Worker&& worker) {
  std::vector<std::thread> pool;
  for (int t = 1; t < nthreads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace netvmo::render
