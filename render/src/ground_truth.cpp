// Ground truth of one camera in one frame, from the true poses: g_wo and g_io, the tag's four
// projected corners in libapriltag's order, whether all of them are in the field of view, and the
// fraction of the printed tag that the camera sees unoccluded (one occlusion ray per sample).
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// A camera-frame point is in the field of view if it is in front, its undistorted normalized
// coordinates lie within those of the image border (guards against the distortion polynomial
// folding far-away points back into the image) and its distorted pixel lies in the image.
bool in_fov(const Intrinsics& Kc, const CameraCache& cc, const Vec3& pc,
            std::optional<Vec2>* uv_out) {
  const auto uv = Kc.project(pc);
  if (uv_out) *uv_out = uv;
  if (!uv) return false;
  const double xn = pc.x() / pc.z(), yn = pc.y() / pc.z();
  const double mx = 0.02 * (cc.xmax - cc.xmin), my = 0.02 * (cc.ymax - cc.ymin);
  if (xn < cc.xmin - mx || xn > cc.xmax + mx || yn < cc.ymin - my || yn > cc.ymax + my)
    return false;
  return uv->x() >= -0.5 && uv->x() <= Kc.width - 0.5 && uv->y() >= -0.5 &&
         uv->y() <= Kc.height - 0.5;
}

// The corners of the black square, c0 (-h,-h), c1 (h,-h), c2 (h,h), c3 (-h,h), on the card
// (bent as its print says), projected.
void project_corners(const Intrinsics& Kc, const CameraCache& cc, const TagTexture& tag,
                     FrameTruth& t) {
  const double h = tag.spec().size / 2;
  const Vec3 corners_o[4] = {tag.card_point(-h, -h), tag.card_point(h, -h), tag.card_point(h, h),
                             tag.card_point(-h, h)};
  t.in_fov = true;
  for (int k = 0; k < 4; ++k) {
    const Vec3 pc = t.g_io * corners_o[k];
    std::optional<Vec2> uv;
    const bool inside = in_fov(Kc, cc, pc, &uv);
    t.corners[size_t(k)] = uv;
    t.in_fov = t.in_fov && inside;
  }
}

// Whether the segment from the camera centre to the world point at `dist` along unit `d` is
// free of geometry (up to just short of the point).
// `time`: the Embree ray time of the frame's time (0.5 with motion blur, else 0).
bool line_of_sight(RTCScene top, RTCIntersectContext* ctx, const Vec3& cam_w, const Vec3& d,
                   double dist, float time) {
  RTCRay ray;
  ray.org_x = float(cam_w.x());
  ray.org_y = float(cam_w.y());
  ray.org_z = float(cam_w.z());
  ray.dir_x = float(d.x());
  ray.dir_y = float(d.y());
  ray.dir_z = float(d.z());
  ray.tnear = 0;
  ray.tfar = float(dist - std::max(1e-4, 1e-5 * dist));
  ray.time = time;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(top, ctx, &ray);
  return ray.tfar >= 0;
}

// Visible fraction: an n x n grid over the printed tag (the black square and its white quiet
// zone, which the detector needs too; on the card, bent as its print says), each sample
// front-facing, in view and with an unobstructed line of sight from the camera centre.
double visible_fraction(RTCScene top, const CameraSpec& cam, const CameraCache& cc,
                        const FrameTruth& t, const Pose& g_wi, const TagTexture& tag, int n,
                        float time) {
  const Vec3 cam_w = g_wi.translation();
  const double hp = 0.5 * tag.printed_side();
  int seen = 0;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (int a = 0; a < n; ++a) {
    // The card's normal depends only on u (a flat card's, or a bent card's along its column).
    const double u = -hp + (2 * hp) * (a + 0.5) / n;
    const Vec3 normal_w = t.g_wo.linear() * tag.card_normal(u);
    for (int b = 0; b < n; ++b) {
      const Vec3 po = tag.card_point(u, -hp + (2 * hp) * (b + 0.5) / n);
      const Vec3 pw = t.g_wo * po;
      const Vec3 to_cam = cam_w - pw;
      if (normal_w.dot(to_cam) <= 0) continue;
      if (!in_fov(cam.intrinsics, cc, t.g_io * po, nullptr)) continue;
      const double dist = to_cam.norm();
      if (line_of_sight(top, &ctx, cam_w, -to_cam / dist, dist, time)) ++seen;
    }
  }
  return double(seen) / double(n * n);
}

}  // namespace

FrameTruth Renderer::truth(int ci, int frame) {
  auto lk = acquire(ci, frame);
  const Impl& I = *impl_;
  const CameraSpec& cam = scene_.cameras[size_t(ci)];
  const CameraCache& cc = I.cams[size_t(ci)];
  FrameTruth t;
  t.frame = frame;
  t.t = time_of(frame);
  t.camera_id = cam.id;
  t.g_wo = I.instances[size_t(I.target_instances.at(0))].g_wb;
  const Pose g_wi = cam.true_pose(t.t);
  t.g_io = g_wi.inverse() * t.g_wo;
  const TagTexture& tag = *I.tags.front();  // the first target's own tag
  project_corners(cam.intrinsics, cc, tag, t);
  t.visible_fraction =
      visible_fraction(I.top, cam, cc, t, g_wi, tag, scene_.imaging.visibility_grid,
                       I.motion_steps > 1 ? 0.5f : 0.0f);  // at the frame's time
  return t;
}

}  // namespace netvmo::render
