// The shading kernel: the radiance of each lane of a traced primary-ray packet. A hit surface
// has the albedo of its tag texture or material, lit by the ambient level plus every light
// (directional, or point with 1 / d^2 falloff) it faces and, for lights with shadows, sees
// along a shadow ray (one shadow packet per light); a miss has the background radiance.
#include <algorithm>
#include <cmath>

#include "renderer_impl.hpp"

namespace netvmo::render {
namespace {

// Lane j of the shadow packet: inactive until shadow_lane sets it up.
void clear_shadow_lane(RayK& sr, int j) {
  sr.org_x[j] = sr.org_y[j] = sr.org_z[j] = 0;
  sr.dir_x[j] = sr.dir_y[j] = 0;
  sr.dir_z[j] = 1;
  sr.tnear[j] = 0;
  sr.tfar[j] = 0;
  sr.time[j] = 0;
  sr.mask[j] = 0xFFFFFFFFu;
  sr.id[j] = unsigned(j);
  sr.flags[j] = 0;
}

// Surface point of lane j: position, normal facing the camera, albedo from the texture, and the
// ambient radiance; a miss gets the background and leaves the packet.
void shade_surface(const Shading& sh, Packet& pk, int j) {
  const RayHitK& rh = pk.rh;
  if (rh.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID) {
    pk.rad[j] = sh.background;
    pk.valid[j] = 0;
    return;
  }
  const Renderer::Impl& I = *sh.impl;
  const unsigned top_id = rh.hit.instID[0][j];
  const GeomInfo& gi = I.instances[size_t(I.instance_of_top_id[top_id])].geoms[rh.hit.geomID[j]];
  const Eigen::Vector3f D(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]);
  const Eigen::Vector3f O(rh.ray.org_x[j], rh.ray.org_y[j], rh.ray.org_z[j]);
  const Eigen::Vector3f P = O + rh.ray.tfar[j] * D;
  const Eigen::Vector3f Ng(rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]);
  Eigen::Vector3f n;
  Eigen::Affine3f moved;  // a motion-blurred instance: world -> shape at the ray's time
  const bool blurred = !sh.steps.empty() && !sh.steps[top_id].empty();
  if (blurred) {
    // Embree interpolates the instance's 3 x 4 transforms linearly between motion steps.
    const auto& S = sh.steps[top_id];
    const int last = int(S.size()) - 1;
    const float x = std::clamp(rh.ray.time[j], 0.0f, 1.0f) * float(last);
    const int i = std::min(int(x), last - 1);
    const float fr = x - float(i);
    Eigen::Affine3f M = Eigen::Affine3f::Identity();
    M.matrix().topRows<3>() = (1 - fr) * S[size_t(i)] + fr * S[size_t(i + 1)];
    n = M.linear() * Ng;
    moved = sh.geom_local[top_id][rh.hit.geomID[j]] * M.inverse();
  } else {
    n = sh.inst_R[top_id] * Ng;
  }
  if (n.dot(D) > 0) n = -n;
  n.normalize();
  const Eigen::Affine3f& wl = blurred ? moved : sh.to_local[top_id][rh.hit.geomID[j]];
  const Eigen::Vector3f pl = wl * P;
  pk.alb[j] = float(gi.tag ? gi.tag->card_albedo(pl.cast<double>())
                           : gi.material.eval(pl.cast<double>(), (wl.linear() * n).cast<double>()));
  pk.gloss[j] = gi.tag ? float(gi.tag->spec().print.gloss) : 0.0f;
  pk.shininess[j] = gi.tag ? float(gi.tag->spec().print.shininess) : 1.0f;
  pk.p[j] = P;
  pk.n[j] = n;
  pk.rad[j] = pk.alb[j] * sh.ambient;
}

// Light L at lane j: adds the unshadowed contribution directly, or sets up the lane's shadow
// ray and keeps the contribution for when the ray is unblocked. Returns whether it cast one.
bool light_lane(const LightF& L, Packet& pk, int j) {
  pk.svalid[j] = 0;
  clear_shadow_lane(pk.sr, j);
  pk.contrib[j] = 0;
  if (!pk.valid[j]) return false;
  Eigen::Vector3f l;
  float e, tfar;
  if (L.directional) {
    l = L.v;
    e = L.intensity;
    tfar = kInf;
  } else {
    l = L.v - pk.p[j];
    const float d2 = std::max(l.squaredNorm(), 1e-6f), d = std::sqrt(d2);
    e = L.intensity / d2;
    l /= d;
    tfar = d - 1e-3f;
  }
  const float c = pk.n[j].dot(l);
  if (c <= 0) return false;
  pk.contrib[j] = pk.alb[j] * e * c;
  if (pk.gloss[j] > 0) {  // Blinn-Phong: h halves the directions to the light and the viewer
    const Eigen::Vector3f view =
        -Eigen::Vector3f(pk.rh.ray.dir_x[j], pk.rh.ray.dir_y[j], pk.rh.ray.dir_z[j]).normalized();
    const float nh = pk.n[j].dot((l + view).normalized());
    if (nh > 0) pk.contrib[j] += pk.gloss[j] * e * std::pow(nh, pk.shininess[j]);
  }
  if (!L.shadows) {
    pk.rad[j] += pk.contrib[j];
    return false;
  }
  const Eigen::Vector3f o = pk.p[j] + 2e-4f * pk.n[j];
  RayK& sr = pk.sr;
  sr.org_x[j] = o.x();
  sr.org_y[j] = o.y();
  sr.org_z[j] = o.z();
  sr.dir_x[j] = l.x();
  sr.dir_y[j] = l.y();
  sr.dir_z[j] = l.z();
  sr.tfar[j] = tfar;
  sr.time[j] = pk.rh.ray.time[j];  // the shadow at the primary ray's time (motion blur)
  pk.svalid[j] = -1;
  return true;
}

// Direct light from L, with one shadow-ray packet.
void add_light(const Shading& sh, const LightF& L, Packet& pk, RTCIntersectContext* sctx) {
  bool any = false;
  for (int j = 0; j < kPacket; ++j) any |= light_lane(L, pk, j);
  if (!any) return;
  occludedK(pk.svalid, sh.impl->top, sctx, &pk.sr);
  for (int j = 0; j < kPacket; ++j)
    if (pk.svalid[j] && pk.sr.tfar[j] >= 0) pk.rad[j] += pk.contrib[j];  // tfar = -inf if blocked
}

}  // namespace

Shading make_shading(const Renderer::Impl& I, const SceneDescription& scene) {
  Shading sh;
  sh.impl = &I;
  for (const auto& l : scene.lights)
    sh.lights.push_back({l.kind == Light::Kind::Directional, l.shadows,
                         l.kind == Light::Kind::Directional
                             ? Eigen::Vector3f((-l.direction.normalized()).cast<float>())
                             : Eigen::Vector3f(l.position.cast<float>()),
                         float(l.intensity)});
  const size_t ninst = I.instance_of_top_id.size();
  sh.inst_R.assign(ninst, Eigen::Matrix3f::Identity());
  sh.to_local.resize(ninst);
  for (size_t t = 0; t < ninst; ++t) {
    if (I.instance_of_top_id[t] < 0) continue;
    const Instance& in = I.instances[size_t(I.instance_of_top_id[t])];
    sh.inst_R[t] = in.g_wb.linear().cast<float>();
    for (const auto& g : in.geoms)
      sh.to_local[t].push_back(Eigen::Affine3f((g.to_local * in.g_bw).cast<float>().matrix()));
  }
  if (I.motion_steps > 1) {
    sh.steps.resize(ninst);
    sh.geom_local.resize(ninst);
    for (size_t t = 0; t < ninst; ++t) {
      if (I.instance_of_top_id[t] < 0) continue;
      const Instance& in = I.instances[size_t(I.instance_of_top_id[t])];
      sh.steps[t] = in.steps;
      for (const auto& g : in.geoms)
        sh.geom_local[t].push_back(Eigen::Affine3f(g.to_local.cast<float>().matrix()));
    }
  }
  sh.ambient = float(scene.imaging.ambient);
  sh.background = float(scene.imaging.background);
  return sh;
}

void shade_packet(const Shading& sh, Packet& pk, RTCIntersectContext* sctx) {
  for (int j = 0; j < kPacket; ++j)
    if (pk.valid[j]) shade_surface(sh, pk, j);
  for (const LightF& L : sh.lights) add_light(sh, L, pk, sctx);
}

}  // namespace netvmo::render
