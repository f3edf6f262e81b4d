// Radiance reuse under motion: conservative bounds of what a moved body can change in a camera's
// image. A packet's cached radiance stays exact unless one of its primary rays can hit a moved
// body's box (at the cached or the current pose), or a shadow ray from one of the points it hit
// towards a light can. Everything else of the scene is unchanged, so such a packet traces to the
// same radiance as before.
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// Margin on every box: covers single-precision tracing (hit points, instance transforms) and
// the shadow rays' offset from the surface (2e-4 along the normal, shading.cpp).
double pad_of(const Eigen::AlignedBox3d& b) {
  return 1e-3 + 1e-6 * std::max(b.min().cwiseAbs().maxCoeff(), b.max().cwiseAbs().maxCoeff());
}

// World box of the instance-frame box `local` at pose g.
Eigen::AlignedBox3d world_box(const Eigen::AlignedBox3d& local, const Eigen::Matrix4d& g) {
  Eigen::AlignedBox3d out;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = local.corner(Eigen::AlignedBox3d::CornerType(c));
    out.extend((g * p.homogeneous()).head<3>());
  }
  return out;
}

// The box's bounds in normalized coordinates of the camera at g_wc.
void project(const Pose& g_wc, MovedBody& b) {
  const Eigen::Matrix3d Rt = g_wc.linear().transpose();
  const Eigen::Vector3d O = g_wc.translation();
  double xmin = kInf, xmax = -kInf, ymin = kInf, ymax = -kInf, zmin = kInf, zmax = -kInf;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d q = Rt * (b.box.corner(Eigen::AlignedBox3d::CornerType(c)) - O);
    zmin = std::min(zmin, q.z());
    zmax = std::max(zmax, q.z());
    if (q.z() <= 0) continue;
    xmin = std::min(xmin, q.x() / q.z());
    xmax = std::max(xmax, q.x() / q.z());
    ymin = std::min(ymin, q.y() / q.z());
    ymax = std::max(ymax, q.y() / q.z());
  }
  const double eps = 1e-9 * (1 + O.cwiseAbs().maxCoeff());
  b.behind = zmax < -eps;
  b.everywhere = !b.behind && zmin <= eps;
  if (b.behind || b.everywhere) return;
  // Camera rays are (xn, yn, 1): inside the convex hull of the corners' projections when they
  // hit the box, all of whose corners are in front.
  const double m =
      1e-5 * (1 + std::max({std::abs(xmin), std::abs(xmax), std::abs(ymin), std::abs(ymax)}));
  b.xmin = float(xmin - m);
  b.xmax = float(xmax + m);
  b.ymin = float(ymin - m);
  b.ymax = float(ymax + m);
}

// Whether the segment o + t d, t in [0, tmax], meets the box.
bool segment_meets(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax,
                   const Eigen::AlignedBox3d& box) {
  double t0 = 0, t1 = tmax;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < box.min()[k] || o[k] > box.max()[k]) return false;
      continue;
    }
    double a = (box.min()[k] - o[k]) / d[k], b = (box.max()[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

bool ray_may_hit(const MovedBody& b, float xn, float yn) {
  const Eigen::Vector3d d(xn, yn, 1.0);
  for (int k = 0; k < 2; ++k)
    if (segment_meets(b.origin[k], b.rotation[k] * d, kInf, b.local)) return true;
  return false;
}

std::vector<MovedBody> moved_bodies(const Renderer::Impl& I,
                                    const std::vector<Eigen::Matrix4d>& cached, const Pose& g_wc) {
  std::vector<MovedBody> out;
  for (size_t i = 0; i < I.instances.size(); ++i) {
    const Instance& in = I.instances[i];
    const Eigen::Matrix4d now = in.g_wb.matrix();
    if (cached[i] == now || in.box.isEmpty()) continue;
    MovedBody b;
    b.box = world_box(in.box, cached[i]).extend(world_box(in.box, now));
    const double pad = pad_of(b.box);
    b.box.min().array() -= pad;
    b.box.max().array() += pad;
    project(g_wc, b);
    b.local = in.box;
    b.local.min().array() -= pad;
    b.local.max().array() += pad;
    const Eigen::Matrix4d g_bw[2] = {cached[i].inverse(), now.inverse()};
    for (int k = 0; k < 2; ++k) {
      b.origin[k] = (g_bw[k] * g_wc.translation().homogeneous()).head<3>();
      b.rotation[k] = g_bw[k].topLeftCorner<3, 3>() * g_wc.linear();
    }
    out.push_back(b);
  }
  return out;
}

bool shadow_may_hit(const MovedBody& b, const LightF& L, const PacketBounds& p) {
  if (!L.shadows || p.no_hit()) return false;
  // Shadow rays from points within `hits` (centre c, half-extents h) to the light lie within
  // the segment from c swept by the box [-h, h]: test that segment against the body's box
  // grown by h.
  const Eigen::Vector3d lo = p.lo.cast<double>(), hi = p.hi.cast<double>();
  const Eigen::Vector3d c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  const Eigen::AlignedBox3d grown(b.box.min() - h, b.box.max() + h);
  if (L.directional) return segment_meets(c, L.v.cast<double>(), kInf, grown);
  return segment_meets(c, L.v.cast<double>() - c, 1.0, grown);
}

}  // namespace netvmo::render
