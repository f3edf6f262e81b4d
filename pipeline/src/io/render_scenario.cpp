#include "netvmo/pipeline/io/render_scenario.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/yaml_reader.hpp"
#include "netvmo/render/geometry.hpp"

namespace netvmo::io {
namespace {

using io::MapReader;
using io::Value;
using render::Pose;
using render::Vec3;

// pose: {p: [x,y,z], r: [rx,ry,rz]} or {eye: [..], look_at: [..], up: [..]} (camera poses).
Pose read_pose(const Value& v) {
  MapReader m = v.map();
  Pose g;
  if (m.has("eye") || m.has("look_at")) {
    const Vec3 eye = m.get("eye").vec<3>();
    const Vec3 at = m.get("look_at").vec<3>();
    const auto up_v = m.find("up");
    const Vec3 up = up_v ? up_v->vec<3>() : Vec3(0, 0, 1);
    try {
      g = render::look_at(eye, at, up);
    } catch (const std::invalid_argument& e) {
      m.fail(e.what());
    }
  } else {
    const auto p = m.find("p");
    const auto r = m.find("r");
    if (!p && !r) m.fail("expected p: [x, y, z] and r: [rx, ry, rz], or eye/look_at/up");
    g = obs::make_pose(p ? p->vec<3>() : Vec3::Zero(), r ? r->vec<3>() : Vec3::Zero());
  }
  m.finish();
  return g;
}

double positive(const Value& v) {
  const double x = v.number();
  if (!(x > 0)) v.fail("must be positive");
  return x;
}

double unit_interval(const Value& v) {
  const double x = v.number();
  if (!(x >= 0 && x <= 1)) v.fail("must be between 0 and 1");
  return x;
}

render::Material read_material(const Value& v) {
  MapReader m = v.map();
  render::Material mat;
  if (const auto p = m.find("pattern")) {
    try {
      mat.pattern = render::parse_pattern(p->string());
    } catch (const std::invalid_argument& e) {
      p->fail(e.what());
    }
  }
  if (const auto a = m.find("albedo")) mat.albedo = unit_interval(*a);
  if (const auto a = m.find("albedo2")) mat.albedo2 = unit_interval(*a);
  if (const auto a = m.find("scale")) mat.scale = positive(*a);
  if (const auto a = m.find("seed")) {
    const int s = a->integer();
    if (s < 0) a->fail("must be >= 0");
    mat.seed = std::uint32_t(s);
  }
  m.finish();
  return mat;
}

render::Shape read_shape(const Value& v, const std::filesystem::path& base_dir) {
  MapReader m = v.map();
  render::Shape s;
  const Value type = m.get("type");
  const std::string t = type.string();
  s.name = m.get_or("name", std::string());
  if (t == "box") {
    s.kind = render::Shape::Kind::Box;
    const Value size = m.get("size");
    s.size = size.vec<3>();
    if (!(s.size.minCoeff() > 0)) size.fail("sizes must be positive");
  } else if (t == "plane") {
    s.kind = render::Shape::Kind::Plane;
    const Value size = m.get("size");
    const auto xy = size.vec<2>();
    if (!(xy.minCoeff() > 0)) size.fail("sizes must be positive");
    s.size = Vec3(xy.x(), xy.y(), 0);
  } else if (t == "cylinder") {
    s.kind = render::Shape::Kind::Cylinder;
    s.size = Vec3(positive(m.get("radius")), 0, positive(m.get("height")));
    if (const auto seg = m.find("segments")) {
      s.segments = seg->integer();
      if (s.segments < 3 || s.segments > 4096) seg->fail("must be between 3 and 4096");
    }
  } else if (t == "obj") {
    s.kind = render::Shape::Kind::Mesh;
    const Value file = m.get("file");
    std::filesystem::path path = file.string();
    if (path.is_relative()) path = base_dir / path;
    std::ifstream in(path);
    if (!in) file.fail("cannot read OBJ file " + path.string());
    std::stringstream ss;
    ss << in.rdbuf();
    try {
      s.mesh = render::parse_obj(ss.str(), path.string());
    } catch (const std::invalid_argument& e) {
      file.fail(e.what());
    }
    if (const auto sc = m.find("scale")) {
      const float k = float(positive(*sc));
      for (auto& p : s.mesh.vertices) p *= k;
    }
  } else {
    type.fail("unknown shape type '" + t + "' (use box, plane, cylinder or obj)");
  }
  if (const auto p = m.find("pose")) s.pose = read_pose(*p);
  if (const auto mat = m.find("material")) s.material = read_material(*mat);
  m.finish();
  return s;
}

std::vector<render::Shape> read_shapes(const Value& v, const std::filesystem::path& base_dir) {
  std::vector<render::Shape> out;
  for (const auto& s : v.sequence()) out.push_back(read_shape(s, base_dir));
  return out;
}

// motion: {type: static, pose}, {type: twist, pose, v, w}, {type: keyframes, keyframes: [{t,
// pose}]}
render::Trajectory read_motion(const Value& v) {
  MapReader m = v.map();
  render::Trajectory tr;
  const Value type = m.get("type");
  const std::string t = type.string();
  if (t == "static") {
    tr.kind = render::Trajectory::Kind::Static;
    tr.g0 = read_pose(m.get("pose"));
  } else if (t == "twist") {
    tr.kind = render::Trajectory::Kind::Twist;
    tr.g0 = read_pose(m.get("pose"));
    const auto lin = m.find("v");
    const auto ang = m.find("w");
    tr.twist.head<3>() = lin ? lin->vec<3>() : Vec3::Zero();
    tr.twist.tail<3>() = ang ? ang->vec<3>() : Vec3::Zero();
  } else if (t == "keyframes") {
    tr.kind = render::Trajectory::Kind::Keyframes;
    const Value kfs = m.get("keyframes");
    for (const auto& k : kfs.sequence()) {
      MapReader km = k.map();
      render::Keyframe kf;
      const Value tv = km.get("t");
      kf.t = tv.number();
      if (!tr.keyframes.empty() && !(kf.t > tr.keyframes.back().t))
        tv.fail("keyframe times must be strictly increasing");
      kf.g = read_pose(km.get("pose"));
      km.finish();
      tr.keyframes.push_back(kf);
    }
    if (tr.keyframes.empty()) kfs.fail("needs at least one keyframe");
    tr.g0 = tr.keyframes.front().g;
  } else {
    type.fail("unknown motion type '" + t + "' (use static, twist or keyframes)");
  }
  m.finish();
  return tr;
}

// A preset name: clean (the defaults) or realistic.
bool read_preset(const Value& v) {
  const std::string p = v.string();
  if (p != "clean" && p != "realistic")
    v.fail("unknown preset '" + p + "' (use clean or realistic)");
  return p == "realistic";
}

// print: clean | realistic | {preset: clean|realistic, ink_spread, gloss, shininess, bend,
// border_width}
// (bend's range depends on the tag's size: read_tag checks it)
render::PrintModel read_print(const Value& v, bool realistic) {
  if (v.node().IsScalar())
    return read_preset(v) ? render::PrintModel::realistic() : render::PrintModel();
  MapReader m = v.map();
  if (const auto p = m.find("preset")) realistic = read_preset(*p);
  render::PrintModel pm = realistic ? render::PrintModel::realistic() : render::PrintModel();
  if (const auto x = m.find("ink_spread")) {
    pm.ink_spread = x->number();
    if (!(std::abs(pm.ink_spread) <= 0.5))
      x->fail("must be between -0.5 and 0.5 (a fraction of a cell, signed)");
  }
  if (const auto x = m.find("gloss")) pm.gloss = unit_interval(*x);
  if (const auto x = m.find("shininess")) {
    pm.shininess = x->number();
    if (!(pm.shininess >= 1 && pm.shininess <= 10000)) x->fail("must be between 1 and 10000");
  }
  if (const auto x = m.find("bend")) pm.bend = x->number();
  if (const auto x = m.find("border_width")) {
    const auto w = x->vec<4>();
    for (int i = 0; i < 4; ++i) {
      if (!(w[i] >= 0.5 && w[i] <= 1.5))
        x->fail("must be four widths [top, right, bottom, left] between 0.5 and 1.5 cells");
      pm.border_width[size_t(i)] = w[i];
    }
  }
  m.finish();
  return pm;
}

// sensor: clean | realistic | {preset: clean|realistic, gain, tone, gamma, full_well, bloom,
// vignetting, vignetting_poly, psf_sigma, jpeg_quality, sharpen_amount, sharpen_sigma,
// exposure_time, line_delay, f_number, focus_distance, focal_length_mm, pixel_pitch_um}
// (render::SensorModel)
render::SensorModel read_sensor(const Value& v, bool realistic) {
  using SM = render::SensorModel;
  if (v.node().IsScalar()) return read_preset(v) ? SM::realistic() : SM();
  MapReader m = v.map();
  if (const auto p = m.find("preset")) realistic = read_preset(*p);
  SM sm = realistic ? SM::realistic() : SM();
  auto in_range = [](const Value& x, double lo, double hi, const std::string& why) {
    const double d = x.number();
    if (!(d >= lo && d <= hi)) x.fail(why);
    return d;
  };
  if (const auto x = m.find("gain")) sm.gain = positive(*x);
  if (const auto x = m.find("tone")) {
    const std::string t = x->string();
    if (t == "linear")
      sm.tone = SM::Tone::Linear;
    else if (t == "srgb")
      sm.tone = SM::Tone::Srgb;
    else if (t == "gamma")
      sm.tone = SM::Tone::Gamma;
    else
      x->fail("unknown tone curve '" + t + "' (use linear, srgb or gamma)");
  }
  if (const auto x = m.find("gamma")) {
    sm.gamma = x->number();
    if (!(sm.gamma > 0 && sm.gamma <= 10)) x->fail("must be > 0 and <= 10");
    if (!m.has("tone")) sm.tone = SM::Tone::Gamma;
  }
  if (const auto x = m.find("full_well"))
    sm.full_well = in_range(*x, 0, 1e6, "must be >= 0 [DN of the linear signal] (0 = none)");
  if (const auto x = m.find("bloom")) sm.bloom = unit_interval(*x);
  if (const auto x = m.find("vignetting")) {
    const std::string t = x->string();
    if (t == "none")
      sm.vignetting = SM::Vignetting::None;
    else if (t == "cos4")
      sm.vignetting = SM::Vignetting::Cos4;
    else if (t == "poly")
      sm.vignetting = SM::Vignetting::Poly;
    else
      x->fail("unknown vignetting '" + t + "' (use none, cos4 or poly)");
  }
  if (const auto x = m.find("vignetting_poly")) {
    const auto a = x->vec<3>();
    for (int i = 0; i < 3; ++i) sm.vignetting_poly[size_t(i)] = a[i];
    if (!m.has("vignetting")) sm.vignetting = SM::Vignetting::Poly;
  }
  if (const auto x = m.find("psf_sigma")) sm.psf_sigma = in_range(*x, 0, 20, "must be 0..20 [px]");
  if (const auto x = m.find("jpeg_quality")) {
    sm.jpeg_quality = x->integer();
    if (sm.jpeg_quality < 0 || sm.jpeg_quality > 100)
      x->fail("must be between 1 and 100 (0 = PNG)");
  }
  if (const auto x = m.find("sharpen_amount"))
    sm.sharpen_amount = in_range(*x, 0, 10, "must be between 0 and 10 (0 = none)");
  if (const auto x = m.find("sharpen_sigma"))
    sm.sharpen_sigma = in_range(*x, 0.1, 20, "must be between 0.1 and 20 [px]");
  if (const auto x = m.find("exposure_time"))
    sm.exposure_time = in_range(*x, 0, 10, "must be between 0 and 10 [s]");
  if (const auto x = m.find("line_delay"))
    sm.line_delay = in_range(*x, -0.01, 0.01, "must be within +-0.01 [s per row]");
  if (const auto x = m.find("f_number")) {
    sm.f_number = x->number();
    if (!(sm.f_number == 0 || (sm.f_number >= 0.5 && sm.f_number <= 1000)))
      x->fail("must be 0 (pinhole) or between 0.5 and 1000");
  }
  if (const auto x = m.find("focus_distance"))
    sm.focus_distance = in_range(*x, 1e-3, 1e6, "must be positive [m]");
  if (const auto x = m.find("focal_length_mm"))
    sm.focal_length_mm = in_range(*x, 0, 1e4, "must be >= 0 [mm]");
  if (const auto x = m.find("pixel_pitch_um"))
    sm.pixel_pitch_um = in_range(*x, 0, 1e3, "must be >= 0 [um]");
  if (sm.f_number > 0 && !(sm.focal_length_mm > 0) && !(sm.pixel_pitch_um > 0))
    v.fail("f_number needs focal_length_mm or pixel_pitch_um (the thin lens's focal length)");
  m.finish();
  return sm;
}

// A tag; `realistic`: the scene's camera_model preset (the print's default).
render::TagSpec read_tag(const Value& v, bool realistic) {
  MapReader m = v.map();
  render::TagSpec tag;
  if (realistic) tag.print = render::PrintModel::realistic();
  tag.family = m.get_or("family", tag.family);
  if (const auto id = m.find("id")) tag.id = id->integer();
  tag.size = positive(m.get("size"));
  if (const auto q = m.find("quiet_cells")) {
    tag.quiet_cells = q->integer();
    if (tag.quiet_cells < 0 || tag.quiet_cells > 100) q->fail("must be between 0 and 100");
  }
  if (const auto w = m.find("white")) tag.white_albedo = unit_interval(*w);
  if (const auto b = m.find("black")) tag.black_albedo = unit_interval(*b);
  if (const auto p = m.find("print")) tag.print = read_print(*p, realistic);
  m.finish();
  try {
    render::TagSpec flat = tag;
    flat.print.bend = 0;
    const render::TagTexture check(flat);  // family and id range, from libapriltag itself
    if (!(std::abs(tag.print.bend) <= check.max_bend()))
      Value(v.node()["print"]["bend"], v.file(), v.path() + ".print.bend")
          .fail("must be " + check.bend_range());
  } catch (const std::invalid_argument& e) {
    v.fail(e.what());
  }
  return tag;
}

render::Intrinsics read_intrinsics(const Value& v) {
  MapReader m = v.map();
  render::Intrinsics k;
  const Value w = m.get("width"), h = m.get("height");
  k.width = w.integer();
  k.height = h.integer();
  if (k.width < 1 || k.width > 16384) w.fail("must be between 1 and 16384");
  if (k.height < 1 || k.height > 16384) h.fail("must be between 1 and 16384");
  k.fx = positive(m.get("fx"));
  k.fy = positive(m.get("fy"));
  // Default principal point: the image centre in OpenCV pixel coordinates.
  k.cx = m.get_or("cx", (k.width - 1) / 2.0);
  k.cy = m.get_or("cy", (k.height - 1) / 2.0);
  // lens: radtan (5 coefficients k1 k2 p1 p2 k3), rational (8: + k4 k5 k6) or fisheye (4: k1..k4,
  // cv::fisheye's equidistant model).
  size_t n = 5;
  if (const auto l = m.find("lens")) {
    const std::string name = l->string();
    if (name == "radtan") {
      k.lens = render::Intrinsics::Lens::RadTan;
    } else if (name == "rational") {
      k.lens = render::Intrinsics::Lens::Rational;
      n = 8;
    } else if (name == "fisheye") {
      k.lens = render::Intrinsics::Lens::Fisheye;
      n = 4;
    } else {
      l->fail("unsupported lens model '" + name + "' (use radtan, rational or fisheye)");
    }
  }
  if (const auto d = m.find("distortion")) {
    const auto c = d->numbers();
    if (c.size() != n)
      d->fail("expected " + std::to_string(n) + " numbers for lens " +
              (n == 5   ? "radtan (k1 k2 p1 p2 k3)"
               : n == 8 ? "rational (k1 k2 p1 p2 k3 k4 k5 k6)"
                        : "fisheye (k1 k2 k3 k4)"));
    for (size_t i = 0; i < n; ++i) k.dist[i] = c[i];
  }
  m.finish();
  return k;
}

render::Light read_light(const Value& v) {
  MapReader m = v.map();
  render::Light l;
  const Value type = m.get("type");
  const std::string t = type.string();
  if (t == "directional") {
    l.kind = render::Light::Kind::Directional;
    const Value d = m.get("direction");
    l.direction = d.vec<3>();
    if (l.direction.norm() < 1e-12) d.fail("must be a non-zero vector");
  } else if (t == "point") {
    l.kind = render::Light::Kind::Point;
    l.position = m.get("position").vec<3>();
  } else {
    type.fail("unknown light type '" + t + "' (use directional or point)");
  }
  if (const auto i = m.find("intensity")) {
    l.intensity = i->number();
    if (l.intensity < 0) i->fail("must be >= 0");
  }
  l.shadows = m.get_or("shadows", l.shadows);
  m.finish();
  return l;
}

// Returns whether imaging.camera_model is realistic (the default of every camera and tag).
bool read_imaging(const Value& v, render::Imaging& im) {
  MapReader m = v.map();
  bool realistic = false;
  if (const auto x = m.find("camera_model")) realistic = read_preset(*x);
  if (const auto x = m.find("spp")) {
    im.spp = x->integer();
    if (im.spp < 1 || im.spp > 1024) x->fail("must be between 1 and 1024");
  }
  if (const auto x = m.find("seed")) {
    const double s = x->number();
    if (s < 0 || s != std::floor(s) || s > 9.0e15) x->fail("must be a non-negative integer");
    im.seed = std::uint64_t(s);
  }
  if (const auto x = m.find("sampling")) {
    const std::string name = x->string();
    if (name == "grid")
      im.sampling = render::Imaging::Sampling::Grid;
    else if (name == "jittered")
      im.sampling = render::Imaging::Sampling::Jittered;
    else
      x->fail("unknown sampling '" + name + "' (use grid or jittered)");
  }
  if (const auto x = m.find("exposure")) im.exposure = positive(*x);
  if (const auto x = m.find("background")) im.background = x->number();
  if (const auto x = m.find("ambient")) im.ambient = x->number();
  im.noise = m.get_or("noise", im.noise);
  if (const auto x = m.find("read_noise")) {
    im.read_noise = x->number();
    if (im.read_noise < 0) x->fail("must be >= 0");
  }
  if (const auto x = m.find("shot_noise")) {
    im.shot_noise = x->number();
    if (im.shot_noise < 0) x->fail("must be >= 0");
  }
  if (const auto x = m.find("threads")) {
    im.threads = x->integer();
    if (im.threads < 0) x->fail("must be >= 0 (0 = all cores)");
  }
  if (const auto x = m.find("tile")) {
    im.tile = x->integer();
    if (im.tile < 1 || im.tile > 1024) x->fail("must be between 1 and 1024");
  }
  if (const auto x = m.find("visibility_grid")) {
    im.visibility_grid = x->integer();
    if (im.visibility_grid < 1 || im.visibility_grid > 256) x->fail("must be between 1 and 256");
  }
  m.finish();
  return realistic;
}

// One `target:` map (or `targets:` entry): tag, extra tags, shapes and motion.
render::Target read_target(const Value& v, const std::filesystem::path& base_dir, bool realistic) {
  MapReader t = v.map();
  render::Target target;
  target.tag = read_tag(t.get("tag"), realistic);
  if (const auto extra = t.find("extra_tags"))
    for (const auto& e : extra->sequence()) {
      MapReader em = e.map();
      render::PlacedTag pt;
      pt.tag = read_tag(em.get("tag"), realistic);
      pt.g_ot = read_pose(em.get("pose"));
      em.finish();
      if (auto why = tags_overlap(target.tag.size, obs::SE3::Identity(), pt.tag.size, pt.g_ot))
        e.fail(*why + " the primary tag; tags of a body must not overlap");
      for (size_t j = 0; j < target.extra_tags.size(); ++j)
        if (auto why = tags_overlap(target.extra_tags[j].tag.size, target.extra_tags[j].g_ot,
                                    pt.tag.size, pt.g_ot))
          e.fail(*why + " extra_tags[" + std::to_string(j) + "]; tags of a body must not overlap");
      target.extra_tags.push_back(pt);
    }
  if (const auto sh = t.find("shapes")) target.shapes = read_shapes(*sh, base_dir);
  target.motion = read_motion(t.get("motion"));
  t.finish();
  return target;
}
}  // namespace

render::SceneDescription load_render_scenario(const std::filesystem::path& file) {
  MapReader root = MapReader::from_file(file);
  const std::filesystem::path base_dir = file.parent_path();
  render::SceneDescription s;
  const Value fps = root.get("fps");
  s.fps = positive(fps);
  const Value frames = root.get("frames");
  s.frames = frames.integer();
  if (s.frames < 1) frames.fail("must be at least 1");
  bool realistic = false;  // imaging.camera_model: realistic
  if (const auto im = root.find("imaging")) realistic = read_imaging(*im, s.imaging);

  s.lights.clear();
  if (const auto ls = root.find("lights"))
    for (const auto& l : ls->sequence()) s.lights.push_back(read_light(l));

  if (root.has("targets")) {
    if (root.has("target")) root.get("target").fail("give either target or targets, not both");
    const Value list = root.get("targets");
    s.targets.clear();
    for (const auto& t : list.sequence()) {
      s.targets.push_back(read_target(t, base_dir, realistic));
      if (s.targets.back().tag.family != s.targets[0].tag.family)
        t.fail("tag.family " + s.targets.back().tag.family +
               ": every target's tag must be of the first target's family (" +
               s.targets[0].tag.family + "), the one family the front end decodes");
    }
    if (s.targets.empty()) list.fail("at least one target is required");
  } else {
    s.targets = {read_target(root.get("target"), base_dir, realistic)};
  }

  const Value cams = root.get("cameras");
  std::set<int> ids;
  for (const auto& c : cams.sequence()) {
    MapReader cm = c.map();
    render::CameraSpec cam;
    cam.id = read_camera_id(cm.get("id"), ids);
    cam.intrinsics = read_intrinsics(cm.get("intrinsics"));
    if (realistic) cam.sensor = render::SensorModel::realistic();
    if (const auto sn = cm.find("sensor")) cam.sensor = read_sensor(*sn, realistic);
    // The true pose: static at `pose`, or following `motion` (then g_wi_true is its t = 0 pose).
    const auto pose = cm.find("pose");
    const auto motion = cm.find("motion");
    if (pose && motion) motion->fail("give either pose or motion, not both");
    if (motion) {
      cam.motion = read_motion(*motion);
      cam.g_wi_true = cam.motion->at(0.0);
    } else {
      cam.g_wi_true = read_pose(cm.get("pose"));
    }
    const auto believed = cm.find("believed");
    const auto offset = cm.find("believed_offset");
    if (believed && offset) offset->fail("give either believed or believed_offset, not both");
    cam.g_wi_believed = cam.g_wi_true;
    if (believed) cam.g_wi_believed = read_pose(*believed);
    if (offset) {
      MapReader om = offset->map();
      const auto dp = om.find("dp");
      const auto dr = om.find("dr");
      // Believed = true pose moved by dp (world) and turned by dr (world rotation vector).
      if (dp) cam.g_wi_believed.translation() += dp->vec<3>();
      if (dr) cam.g_wi_believed.linear() = obs::exp_so3(dr->vec<3>()) * cam.g_wi_true.linear();
      om.finish();
    }
    if (const auto drift = cm.find("believed_drift")) {
      // The believed world frame drifts: dp [m/s] and dr [rad/s] (CameraSpec::believed_pose).
      MapReader dm = drift->map();
      if (const auto dp = dm.find("dp")) cam.believed_drift.head<3>() = dp->vec<3>();
      if (const auto dr = dm.find("dr")) cam.believed_drift.tail<3>() = dr->vec<3>();
      dm.finish();
    }
    // Its own clock (the scene's by default): images at start + k / fps.
    if (const auto f = cm.find("fps")) cam.fps = positive(*f);
    if (const auto st = cm.find("start")) {
      cam.start = st->number();
      if (!(cam.start >= 0)) st->fail("must be >= 0 (seconds)");
    }
    cm.finish();
    s.cameras.push_back(cam);
  }
  if (s.cameras.empty()) cams.fail("needs at least one camera");

  if (const auto occ = root.find("occluders"))
    for (const auto& o : occ->sequence()) {
      MapReader om = o.map();
      render::Body b;
      b.name = om.get_or("name", std::string("occluder"));
      b.shapes = read_shapes(om.get("shapes"), base_dir);
      if (const auto mo = om.find("motion")) b.motion = read_motion(*mo);
      om.finish();
      s.occluders.push_back(std::move(b));
    }

  if (const auto edges = root.find("edges")) s.edges = read_edges(*edges, ids);
  root.finish();

  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string() + ": " + e.what());
  }
  return s;
}

NetworkConfig scene_network_config(const render::SceneDescription& scene, int frames) {
  NetworkConfig net;
  net.fps = scene.fps;
  net.frames = frames;
  net.targets.clear();
  for (const auto& body : scene.targets) {
    TargetConfig target;
    target.family = body.tag.family;
    target.id = body.tag.id;
    target.size = body.tag.size;
    // The body's other tags are its bundle (ground truth: g_wo composed with each g_ot). An
    // extra tag repeating an id already on the body (tag_cube.yaml's decoys) or of another
    // family cannot be told apart by the detector's one family: rendered, not written.
    std::set<int> ids{target.id};
    for (const auto& e : body.extra_tags)
      if (e.tag.family == target.family && ids.insert(e.tag.id).second)
        target.bundle.push_back({e.tag.id, e.tag.size, e.g_ot});
    net.targets.push_back(target);
  }
  for (const auto& c : scene.cameras) net.cameras.push_back({c.id, c.g_wi_believed, c.fps, {}, {}});
  net.edges = scene.edges;
  net.source = "the scene";
  return net;
}

Calibration scene_calibration(const render::CameraSpec& c) {
  Calibration k;
  k.width = c.intrinsics.width;
  k.height = c.intrinsics.height;
  k.K = cv::Matx33d(c.intrinsics.fx, 0, c.intrinsics.cx, 0, c.intrinsics.fy, c.intrinsics.cy, 0, 0,
                    1);
  const auto& d = c.intrinsics.dist;
  switch (c.intrinsics.lens) {
    case render::Intrinsics::Lens::Fisheye:
      k.fisheye = true;
      for (int j = 0; j < 4; ++j) k.dist[j] = d[size_t(j)];
      break;
    case render::Intrinsics::Lens::Rational:
      for (int j = 0; j < 3; ++j) k.rational[j] = d[size_t(5 + j)];
      [[fallthrough]];
    case render::Intrinsics::Lens::RadTan:
      for (int j = 0; j < 5; ++j) k.dist[j] = d[size_t(j)];
      break;
  }
  k.source = "camera " + std::to_string(c.id) + " of the scene";
  return k;
}

}  // namespace netvmo::io
