// The render loop, in layers: a frame is split into square tiles that the threads take in turn;
// a tile is traced in packets of kPacket samples covering small square pixel blocks (coherent
// primary and shadow rays), each packet shaded by the kernel (shading.cpp), and the tile's
// radiance goes through the sensor (sensor.cpp). A camera reuses its last image's radiance
// wherever no moved body or its shadow can have changed it (reuse_bounds.cpp) and re-traces the
// rest; in either case the frame draws new noise. A camera whose pose changed since its last
// image (a moving camera) traces it in full.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// Where a frame's radiance comes from: traced in full, reused in full, or reused except where a
// moved body or its shadow can reach.
enum class Radiance { Trace, Reuse, Partial };

// What every tile of one image shares.
struct FrameJob {
  FrameJob(const Renderer::Impl& I, const SceneDescription& scene, int ci, int frame, double t,
           cv::Mat& out)
      : impl(I),
        cc(I.cams[size_t(ci)]),
        im(scene.imaging),
        camera_id(scene.cameras[size_t(ci)].id),
        frame(frame),
        tile(im.tile),
        tiles_x((cc.width + tile - 1) / tile),
        ntiles(tiles_x * ((cc.height + tile - 1) / tile)),
        block(std::max(1, int(std::lround(std::sqrt(double(kPacket) / cc.spp))))),
        scale(255.0 * im.exposure / cc.spp),
        chunk(std::lcm(block * block * cc.spp, kPacket)),
        shading(make_shading(I, scene)),
        cache(*I.radiance[size_t(ci)]),
        out(out),
        develop(scene.cameras[size_t(ci)].sensor.image_effects()) {
    const CameraSpec& cam = scene.cameras[size_t(ci)];
    g_wc = cam.true_pose(t);  // the camera's true pose at this frame's time
    R = g_wc.linear().cast<float>();
    O = g_wc.translation().cast<float>();
    const Intrinsics& Kc = cam.intrinsics;
    // The realistic camera's rays: each sample at its own time in the exposure (and its row's
    // rolling-shutter offset) and through its own point of the lens aperture.
    const SensorModel& sm = cam.sensor;
    timed = I.motion_steps > 1;
    lens = sm.lens_effects();
    if (timed || lens) {
      exposure_time = sm.exposure_time;
      line_delay = sm.line_delay;
      row_mid = 0.5 * (Kc.height - 1);
      half_window = I.half_window;
      lens_radius = float(0.5 * sm.aperture(Kc.fx));
      focus = float(sm.focus_distance);
      std::uint64_t h = im.seed ^ 0x5bd1e9955bd1e995ULL;
      jitter_seed =
          mix64(mix64(h) ^ (std::uint64_t(std::uint32_t(camera_id)) << 32 | std::uint32_t(frame)));
      if (timed && cam.moving())  // the camera's own pose at the motion steps
        for (int k = 0; k < I.motion_steps; ++k) {
          const Pose g = cam.true_pose(t + (2.0 * k / (I.motion_steps - 1) - 1.0) * half_window);
          cam_R.push_back(g.linear().cast<float>());
          cam_O.push_back(g.translation().cast<float>());
        }
    }
  }

  const Renderer::Impl& impl;
  const CameraCache& cc;
  const Imaging& im;
  int camera_id, frame;
  int tile, tiles_x, ntiles;  // (the image's size and samples per pixel: cc's)
  int block;     // packets cover block x block pixels with all their samples (~kPacket rays)
  double scale;  // summed radiance of a pixel -> DN
  // Samples traced or reused together: whole packets covering whole pixel blocks, so a traced
  // pixel's sum has the same packets in the same order as in a full trace.
  int chunk;
  std::vector<int> first_packet;  // per tile: index of its first packet in cache.packets
  Shading shading;
  RadianceCache& cache;
  Radiance source = Radiance::Trace;
  std::vector<MovedBody> moved;        // Partial: the bodies that moved since the cached image
  mutable std::atomic<int> traced{0};  // packets traced
  cv::Mat& out;
  bool develop;  // SensorModel::image_effects(): the whole image goes through develop_image
  Pose g_wc;
  Eigen::Matrix3f R;  // camera -> world
  Eigen::Vector3f O;  // camera centre
  // Realistic rays (SensorModel): per-lane time (motion blur, rolling shutter) and lens point.
  bool timed = false, lens = false;
  double exposure_time = 0, line_delay = 0, row_mid = 0, half_window = 0;
  float lens_radius = 0, focus = 1;
  std::uint64_t jitter_seed = 0;       // from (seed, camera id, frame): per-pixel sample rotation
  std::vector<Eigen::Matrix3f> cam_R;  // a moving camera's pose at the motion steps
  std::vector<Eigen::Vector3f> cam_O;
};

// A tile: its origin and size in the image, and how its samples are ordered into packets.
struct TileRect {
  int index, x0, y0, w, h;
  int bxn;        // pixel blocks per tile row
  int per_block;  // samples per block
  int nsamples;   // samples in the tile, whole blocks (a block may overhang a partial tile)
};

TileRect tile_rect(const FrameJob& f, int tile) {
  TileRect t;
  t.index = tile;
  t.x0 = (tile % f.tiles_x) * f.tile;
  t.y0 = (tile / f.tiles_x) * f.tile;
  t.w = std::min(f.tile, f.cc.width - t.x0);
  t.h = std::min(f.tile, f.cc.height - t.y0);
  t.bxn = (t.w + f.block - 1) / f.block;
  t.per_block = f.block * f.block * f.cc.spp;
  t.nsamples = t.bxn * ((t.h + f.block - 1) / f.block) * t.per_block;
  return t;
}

// A render thread's state, reused from tile to tile.
struct TileWorker {
  explicit TileWorker(int tile) : acc(size_t(tile * tile)) {
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    // Shadow packets stay INCOHERENT: with RTC_INTERSECT_CONTEXT_FLAG_COHERENT, rtcOccluded16 of
    // Debian's Embree 3.13.5 never returned on this machine (AVX-512), whatever the tfar values.
    rtcInitIntersectContext(&sctx);
  }
  RTCIntersectContext ctx, sctx;
  Packet pk;
  std::vector<float> acc;  // the tile's radiance per pixel, summed over samples
  int traced = 0;          // packets traced
};

// Lane j of the packet, inactive until primary_lane aims it.
void clear_lane(RayHitK& rh, const Eigen::Vector3f& O, int j) {
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
}

// Sample `idx` of the tile (consecutive samples of neighbouring pixels of one block): its pixel
// (cin, rin) in the tile and sample s; false when the tile has run out of samples or the block
// overhangs a partial tile.
bool tile_sample(const FrameJob& f, const TileRect& t, int idx, int& cin, int& rin, int& s) {
  if (idx >= t.nsamples) return false;
  const int blk = idx / t.per_block, w = idx % t.per_block, pib = w / f.cc.spp;
  s = w % f.cc.spp;
  cin = (blk % t.bxn) * f.block + pib % f.block;
  rin = (blk / t.bxn) * f.block + pib / f.block;
  return cin < t.w && rin < t.h;
}

double radical_inverse(unsigned i, unsigned base) {
  double r = 0, f = 1.0 / base;
  for (; i; i /= base, f /= base) r += f * (i % base);
  return r;
}

// The realistic part of lane j's ray for sample s of pixel (col, row) through undistorted
// normalized (xn, yn): its time in the exposure (radical inverse base 3 of s) and lens point
// (bases 5 and 7, concentric disc mapping), each rotated by a per-pixel seeded offset.
void realistic_lane(const FrameJob& f, int col, int row, int s, float xn, float yn, Packet& pk,
                    int j) {
  const std::uint64_t h =
      mix64(f.jitter_seed ^ (std::uint64_t(row) * 0x100000001b3ULL + std::uint64_t(col)));
  auto rot = [&](double u, int k) {
    const double o = double((h >> (21 * k)) & 0x1FFFFF) / 2097152.0;
    const double v = u + o;
    return v >= 1 ? v - 1 : v;
  };
  Eigen::Matrix3f R = f.R;
  Eigen::Vector3f O = f.O;
  float time = 0;
  if (f.timed) {
    const double dt = (row - f.row_mid) * f.line_delay +
                      (rot(radical_inverse(unsigned(s), 3), 0) - 0.5) * f.exposure_time;
    time = float(std::clamp(0.5 + 0.5 * dt / f.half_window, 0.0, 1.0));
    if (!f.cam_R.empty()) {  // the moving camera at the ray's time, interpolated as bodies are
      const int last = int(f.cam_R.size()) - 1;
      const float x = time * float(last);
      const int i = std::min(int(x), last - 1);
      const float fr = x - float(i);
      R = (1 - fr) * f.cam_R[size_t(i)] + fr * f.cam_R[size_t(i + 1)];
      O = (1 - fr) * f.cam_O[size_t(i)] + fr * f.cam_O[size_t(i + 1)];
    }
  }
  Eigen::Vector3f d(xn, yn, 1.0f);
  if (f.lens) {
    // Thin lens: the ray leaves lens point l (camera frame, z = 0) towards the point of the
    // pinhole ray on the plane in focus, (xn, yn, 1) * focus.
    const double a = 2 * rot(radical_inverse(unsigned(s), 5), 1) - 1;
    const double b = 2 * rot(radical_inverse(unsigned(s), 7), 2) - 1;
    double r = 0, phi = 0;  // Shirley and Chiu's concentric mapping of the square to the disc
    if (a != 0 || b != 0) {
      if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = M_PI / 4 * (b / a);
      } else {
        r = b;
        phi = M_PI / 2 - M_PI / 4 * (a / b);
      }
    }
    const Eigen::Vector3f l(float(f.lens_radius * r * std::cos(phi)),
                            float(f.lens_radius * r * std::sin(phi)), 0.0f);
    d = Eigen::Vector3f(xn - l.x() / f.focus, yn - l.y() / f.focus, 1.0f);
    O += R * l;
  }
  d = R * d;
  pk.rh.ray.org_x[j] = O.x();
  pk.rh.ray.org_y[j] = O.y();
  pk.rh.ray.org_z[j] = O.z();
  pk.rh.ray.dir_x[j] = d.x();
  pk.rh.ray.dir_y[j] = d.y();
  pk.rh.ray.dir_z[j] = d.z();
  pk.rh.ray.time[j] = time;
}

// Pixel level: lane j takes sample `idx` of the tile, if it has one; `pb` bounds the rays.
void primary_lane(const FrameJob& f, const TileRect& t, int idx, int j, Packet& pk,
                  PacketBounds& pb) {
  pk.valid[j] = 0;
  pk.pix[j] = -1;
  pk.rad[j] = 0;
  clear_lane(pk.rh, f.O, j);
  int cin, rin, s;
  if (!tile_sample(f, t, idx, cin, rin, s)) return;
  pk.pix[j] = rin * t.w + cin;
  float xn, yn;
  if (!primary_ray(f.cc, f.impl.offsets, t.x0 + cin, t.y0 + rin, s, xn, yn)) return;
  pb.xmin = std::min(pb.xmin, xn);
  pb.xmax = std::max(pb.xmax, xn);
  pb.ymin = std::min(pb.ymin, yn);
  pb.ymax = std::max(pb.ymax, yn);
  pk.valid[j] = -1;
  if (f.timed || f.lens) return realistic_lane(f, t.x0 + cin, t.y0 + rin, s, xn, yn, pk, j);
  const Eigen::Vector3f d = f.R * Eigen::Vector3f(xn, yn, 1.0f);
  pk.rh.ray.dir_x[j] = d.x();
  pk.rh.ray.dir_y[j] = d.y();
  pk.rh.ray.dir_z[j] = d.z();
}

// Packet level: aim, trace and shade kPacket samples from `base` on; add them to their pixels
// and keep the bounds of their rays and of the surface points they hit.
void trace_packet(const FrameJob& f, const TileRect& t, int base, TileWorker& w, PacketBounds& pb) {
  Packet& pk = w.pk;
  pb = PacketBounds();
  for (int j = 0; j < kPacket; ++j) primary_lane(f, t, base + j, j, pk, pb);
  intersectK(pk.valid, f.impl.top, &w.ctx, &pk.rh);
  shade_packet(f.shading, pk, &w.sctx);
  for (int j = 0; j < kPacket; ++j) {
    if (pk.pix[j] >= 0) w.acc[size_t(pk.pix[j])] += pk.rad[j];
    if (pk.valid[j]) {  // a hit (shading clears the lanes that missed)
      pb.lo = pb.lo.cwiseMin(pk.p[j]);
      pb.hi = pb.hi.cwiseMax(pk.p[j]);
    }
  }
}

// Whether a primary ray of the packet of samples [base, base + kPacket) may hit the body.
bool rays_may_hit(const FrameJob& f, const TileRect& t, int base, const MovedBody& b) {
  for (int idx = base; idx < base + kPacket; ++idx) {
    int cin, rin, s;
    float xn, yn;
    if (tile_sample(f, t, idx, cin, rin, s) &&
        primary_ray(f.cc, f.impl.offsets, t.x0 + cin, t.y0 + rin, s, xn, yn) &&
        ray_may_hit(b, xn, yn))
      return true;
  }
  return false;
}

// Whether a moved body or its shadow can reach samples [c0, c1) of the tile: one of their
// primary rays may hit it (bounds of the packets' rays first, then ray by ray), or a shadow ray
// from a point they hit last time may.
bool chunk_touched(const FrameJob& f, const TileRect& t, int c0, int c1, const PacketBounds* pb) {
  for (int base = c0; base < c1; base += kPacket) {
    const PacketBounds& p = pb[base / kPacket];
    for (const MovedBody& b : f.moved) {
      if (primary_may_hit(b, p) && rays_may_hit(f, t, base, b)) return true;
      for (const LightF& L : f.shading.lights)
        if (shadow_may_hit(b, L, p)) return true;
    }
  }
  return false;
}

// Clears the radiance of the pixels of samples [c0, c1) before they are traced again.
void clear_chunk(const FrameJob& f, const TileRect& t, int c0, int c1, TileWorker& w) {
  for (int idx = c0; idx < c1; ++idx) {
    int cin, rin, s;
    if (tile_sample(f, t, idx, cin, rin, s)) w.acc[size_t(rin * t.w + cin)] = 0.0f;
  }
}

// Copies a tile's radiance between the worker's buffer and the camera's radiance cache.
void copy_radiance(const FrameJob& f, const TileRect& t, TileWorker& w, bool to_cache) {
  for (int y = 0; y < t.h; ++y)
    for (int x = 0; x < t.w; ++x) {
      float& cached = f.cache.acc[size_t(t.y0 + y) * size_t(f.cc.width) + size_t(t.x0 + x)];
      float& mine = w.acc[size_t(y * t.w + x)];
      if (to_cache)
        cached = mine;
      else
        mine = cached;
    }
}

// Tile level: radiance (traced, reused from the cache, or reused where nothing can have changed
// and traced elsewhere, chunk by chunk), then the sensor.
void render_tile(const FrameJob& f, int tile, TileWorker& w) {
  const TileRect t = tile_rect(f, tile);
  std::fill(w.acc.begin(), w.acc.end(), 0.0f);
  if (f.source != Radiance::Trace) copy_radiance(f, t, w, false);
  if (f.source != Radiance::Reuse) {
    PacketBounds* pb = f.cache.packets.data() + f.first_packet[size_t(tile)];
    bool traced = false;
    for (int c0 = 0; c0 < t.nsamples; c0 += f.chunk) {
      const int c1 = std::min(c0 + f.chunk, t.nsamples);
      const int np = (c1 - c0 + kPacket - 1) / kPacket;
      if (f.source == Radiance::Partial) {
        if (!chunk_touched(f, t, c0, c1, pb)) continue;
        clear_chunk(f, t, c0, c1, w);
      }
      for (int base = c0; base < c1; base += kPacket)
        trace_packet(f, t, base, w, pb[base / kPacket]);
      w.traced += np;
      traced = true;
    }
    if (traced) copy_radiance(f, t, w, true);
  }
  if (f.develop) return;  // the realistic sensor works on the whole image (develop_image)
  expose_tile(f.im, f.scale, tile_seed(f.im.seed, f.camera_id, f.frame, tile), w.acc, t.x0, t.y0,
              t.w, t.h, f.out);
}

// One render thread: takes the next tile until none is left.
void render_tiles(const FrameJob& f, std::atomic<int>& next) {
  TileWorker w(f.tile);
  for (int tile = next++; tile < f.ntiles; tile = next++) render_tile(f, tile, w);
  f.traced += w.traced;
}

}  // namespace

// Frame level: the camera's radiance cache and what moved since it was filled decide between
// tracing, reuse and partial reuse; the threads share out the tiles.
cv::Mat Renderer::render(int ci, int frame) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const Intrinsics& Kc = scene_.cameras[size_t(ci)].intrinsics;
  cv::Mat out(Kc.height, Kc.width, CV_8UC1);
  FrameJob f(I, scene_, ci, frame, time_of(frame), out);
  int packets = 0;
  for (int tile = 0; tile < f.ntiles; ++tile) {
    f.first_packet.push_back(packets);
    packets += (tile_rect(f, tile).nsamples + kPacket - 1) / kPacket;
  }
  std::unique_lock<std::mutex> cache_lock(f.cache.mutex);
  std::vector<Eigen::Matrix4d> key;
  for (const auto& in : I.instances) key.push_back(in.g_wb.matrix());
  // A camera that moved sees every ray change: its whole image is traced again.
  // Motion blur and defocus: rays leave the camera at other times and points; no reuse.
  if (!f.im.reuse_radiance || !f.cache.valid || f.cache.camera != f.g_wc.matrix() || f.timed ||
      f.lens) {
    f.source = Radiance::Trace;
    f.cache.acc.assign(size_t(f.cc.width) * size_t(f.cc.height), 0.0f);
    f.cache.packets.assign(size_t(packets), PacketBounds());
  } else if (f.cache.key == key) {
    f.source = Radiance::Reuse;
  } else {
    f.source = Radiance::Partial;
    f.moved = moved_bodies(I, f.cache.key, f.g_wc);
  }
  f.cache.valid = false;  // until every tile is done
  const int hw = int(std::max(1u, std::thread::hardware_concurrency()));
  const int nthreads = std::max(1, std::min(f.ntiles, f.im.threads > 0 ? f.im.threads : hw));
  std::atomic<int> next{0};
  run_threads(nthreads, [&]() { render_tiles(f, next); });
  if (f.develop) {
    const CameraSpec& cam = scene_.cameras[size_t(ci)];
    develop_image(cam.sensor, f.im, Kc, f.scale, cam.id, frame, f.cache.acc, out);
  }
  f.cache.key = std::move(key);
  f.cache.camera = f.g_wc.matrix();
  f.cache.traced_fraction = double(f.traced) / double(std::max(1, packets));
  f.cache.valid = true;
  return out;
}

double Renderer::traced_fraction(int ci) {
  if (ci < 0 || ci >= camera_count()) throw std::invalid_argument("camera index out of range");
  RadianceCache& c = *impl_->radiance[size_t(ci)];
  std::lock_guard<std::mutex> lock(c.mutex);
  return c.traced_fraction;
}

}  // namespace netvmo::render
