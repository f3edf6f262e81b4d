// Benchmark baseline: render()'s primary rays traced one at a time with rtcIntersect1, no
// shading, rows shared out over the threads.
#include <atomic>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// Whether the ray from O along d hits anything.
bool hits(RTCScene top, RTCIntersectContext* ctx, const Eigen::Vector3f& O,
          const Eigen::Vector3f& d) {
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
  rtcIntersect1(top, ctx, &r);
  return r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

// The hits of every sample of one image row.
std::uint64_t row_hits(const Renderer::Impl& I, const CameraCache& cc, const Pose& g_wc, int row,
                       RTCIntersectContext* ctx) {
  const Eigen::Matrix3f R = g_wc.linear().cast<float>();
  const Eigen::Vector3f O = g_wc.translation().cast<float>();
  std::uint64_t n = 0;
  for (int col = 0; col < cc.width; ++col)
    for (int s = 0; s < cc.spp; ++s) {
      float xn, yn;
      if (primary_ray(cc, I.offsets, col, row, s, xn, yn))
        n += hits(I.top, ctx, O, R * Eigen::Vector3f(xn, yn, 1.0f));
    }
  return n;
}

}  // namespace

std::uint64_t Renderer::intersect_bare(int ci, int frame, int threads) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const CameraSpec& cam = scene_.cameras[size_t(ci)];
  const CameraCache& cc = I.cams[size_t(ci)];
  const Pose g_wc = camera_pose(ci, frame);
  std::atomic<int> next_row{0};
  std::atomic<std::uint64_t> total{0};
  run_threads(std::max(1, threads), [&]() {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    std::uint64_t local = 0;
    for (int row = next_row++; row < cam.intrinsics.height; row = next_row++)
      local += row_hits(I, cc, g_wc, row, &ctx);
    total += local;
  });
  return total;
}

}  // namespace netvmo::render
