// The render loop, in layers: a frame is split into square tiles that the threads take in turn;
// a tile is traced in packets of kPacket samples covering small square pixel blocks (coherent
// primary and shadow rays), each packet shaded by the kernel (shading.cpp), and the tile's
// radiance goes through the sensor (sensor.cpp). A camera whose scene has not moved since its
// last image reuses that image's radiance and draws new noise only.
#include <atomic>
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// What every tile of one image shares.
struct FrameJob {
  FrameJob(const Renderer::Impl& I, const SceneDescription& scene, int ci, int frame, cv::Mat& out)
      : impl(I),
        cc(I.cams[size_t(ci)]),
        im(scene.imaging),
        camera_id(scene.cameras[size_t(ci)].id),
        frame(frame),
        width(out.cols),
        height(out.rows),
        tile(im.tile),
        tiles_x((width + tile - 1) / tile),
        ntiles(tiles_x * ((height + tile - 1) / tile)),
        spp(int(I.offsets.size())),
        block(std::max(1, int(std::lround(std::sqrt(double(kPacket) / spp))))),
        scale(255.0 * im.exposure / spp),
        shading(make_shading(I, scene)),
        cache(*I.radiance[size_t(ci)]),
        out(out) {
    const CameraSpec& cam = scene.cameras[size_t(ci)];
    R = cam.g_wi_true.linear().cast<float>();
    O = cam.g_wi_true.translation().cast<float>();
    const Intrinsics& Kc = cam.intrinsics;
    fx = float(Kc.fx), fy = float(Kc.fy), cx = float(Kc.cx), cy = float(Kc.cy);
  }

  const Renderer::Impl& impl;
  const CameraCache& cc;
  const Imaging& im;
  int camera_id, frame;
  int width, height, tile, tiles_x, ntiles, spp;
  int block;     // packets cover block x block pixels with all their samples (~kPacket rays)
  double scale;  // summed radiance of a pixel -> DN
  Shading shading;
  RadianceCache& cache;
  bool reuse = false;  // trace nothing: take the radiance from `cache`
  cv::Mat& out;
  Eigen::Matrix3f R;  // camera -> world
  Eigen::Vector3f O;  // camera centre
  float fx = 0, fy = 0, cx = 0, cy = 0;
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
  t.w = std::min(f.tile, f.width - t.x0);
  t.h = std::min(f.tile, f.height - t.y0);
  t.bxn = (t.w + f.block - 1) / f.block;
  t.per_block = f.block * f.block * f.spp;
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

// Undistorted normalized coordinates of sample s of pixel (col, row); false outside the region
// where the distortion model is invertible (the sample stays black).
bool camera_ray(const FrameJob& f, int col, int row, int s, float& xn, float& yn) {
  if (f.cc.table.empty()) {
    xn = (float(col) + f.impl.offsets[size_t(s)].x() - f.cx) / f.fx;
    yn = (float(row) + f.impl.offsets[size_t(s)].y() - f.cy) / f.fy;
    return true;
  }
  const size_t ti = ray_table_index(row, col, s, f.width, f.spp);
  xn = f.cc.table[ti];
  yn = f.cc.table[ti + 1];
  return std::isfinite(xn);
}

// Pixel level: lane j takes sample `idx` of the tile (consecutive samples of neighbouring pixels
// of one block), unless the tile has run out of samples or the block overhangs a partial tile.
void primary_lane(const FrameJob& f, const TileRect& t, int idx, int j, Packet& pk) {
  pk.valid[j] = 0;
  pk.pix[j] = -1;
  pk.rad[j] = 0;
  clear_lane(pk.rh, f.O, j);
  if (idx >= t.nsamples) return;
  const int blk = idx / t.per_block, w = idx % t.per_block, pib = w / f.spp, s = w % f.spp;
  const int cin = (blk % t.bxn) * f.block + pib % f.block;
  const int rin = (blk / t.bxn) * f.block + pib / f.block;
  if (cin >= t.w || rin >= t.h) return;
  pk.pix[j] = rin * t.w + cin;
  float xn, yn;
  if (!camera_ray(f, t.x0 + cin, t.y0 + rin, s, xn, yn)) return;
  const Eigen::Vector3f d = f.R * Eigen::Vector3f(xn, yn, 1.0f);
  pk.rh.ray.dir_x[j] = d.x();
  pk.rh.ray.dir_y[j] = d.y();
  pk.rh.ray.dir_z[j] = d.z();
  pk.valid[j] = -1;
}

// Packet level: aim, trace and shade kPacket samples from `base` on; add them to their pixels.
void trace_packet(const FrameJob& f, const TileRect& t, int base, TileWorker& w) {
  Packet& pk = w.pk;
  for (int j = 0; j < kPacket; ++j) primary_lane(f, t, base + j, j, pk);
  intersectK(pk.valid, f.impl.top, &w.ctx, &pk.rh);
  shade_packet(f.shading, f.O, pk, &w.sctx);
  for (int j = 0; j < kPacket; ++j)
    if (pk.pix[j] >= 0) w.acc[size_t(pk.pix[j])] += pk.rad[j];
}

// Copies a tile's radiance between the worker's buffer and the camera's radiance cache.
void copy_radiance(const FrameJob& f, const TileRect& t, TileWorker& w, bool to_cache) {
  for (int y = 0; y < t.h; ++y)
    for (int x = 0; x < t.w; ++x) {
      float& cached = f.cache.acc[size_t(t.y0 + y) * size_t(f.width) + size_t(t.x0 + x)];
      float& mine = w.acc[size_t(y * t.w + x)];
      if (to_cache)
        cached = mine;
      else
        mine = cached;
    }
}

// Tile level: radiance (traced, or reused from the cache), then the sensor.
void render_tile(const FrameJob& f, int tile, TileWorker& w) {
  const TileRect t = tile_rect(f, tile);
  std::fill(w.acc.begin(), w.acc.end(), 0.0f);
  if (f.reuse) copy_radiance(f, t, w, false);
  for (int base = f.reuse ? t.nsamples : 0; base < t.nsamples; base += kPacket)
    trace_packet(f, t, base, w);
  if (!f.reuse) copy_radiance(f, t, w, true);
  expose_tile(f.im, f.scale, tile_seed(f.im.seed, f.camera_id, f.frame, tile), w.acc, t.x0, t.y0,
              t.w, t.h, f.out);
}

// One render thread: takes the next tile until none is left.
void render_tiles(const FrameJob& f, std::atomic<int>& next) {
  TileWorker w(f.tile);
  for (int tile = next++; tile < f.ntiles; tile = next++) render_tile(f, tile, w);
}

}  // namespace

// Frame level: the camera's radiance cache decides between tracing and reuse, the threads share
// out the tiles.
cv::Mat Renderer::render(int ci, int frame) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const Intrinsics& Kc = scene_.cameras[size_t(ci)].intrinsics;
  cv::Mat out(Kc.height, Kc.width, CV_8UC1);
  FrameJob f(I, scene_, ci, frame, out);
  std::unique_lock<std::mutex> cache_lock(f.cache.mutex);
  std::vector<Eigen::Matrix4d> key;
  for (const auto& in : I.instances) key.push_back(in.g_wb.matrix());
  f.reuse = f.im.reuse_static && f.cache.valid && f.cache.key == key;
  if (!f.reuse) {
    f.cache.valid = false;
    f.cache.acc.assign(size_t(f.width) * size_t(f.height), 0.0f);
  }
  const int hw = int(std::max(1u, std::thread::hardware_concurrency()));
  const int nthreads = std::max(1, std::min(f.ntiles, f.im.threads > 0 ? f.im.threads : hw));
  std::atomic<int> next{0};
  run_threads(nthreads, [&]() { render_tiles(f, next); });
  if (!f.reuse) {
    f.cache.key = std::move(key);
    f.cache.valid = true;
  }
  return out;
}

}  // namespace netvmo::render
