// `netvmo calibrate`: camera poses from tags. The tags seen through the front end, the initial
// poses, the bundle adjustment (bundle_adjustment.hpp) with a map or with a moved tag, and the
// per-camera results (calibrate.hpp has the model and docs/calibration.md the derivations).
#include "netvmo/pipeline/calib/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "bundle_adjustment.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/stopwatch.hpp"

namespace netvmo::calib {

using detail::Ba;
using detail::by_image;
using detail::camera_covariances;
using detail::image_pnp;
using detail::mean_pose;
using detail::naive_pnp;
using detail::robust_cost;
using detail::solve;
using detail::TagSeen;

namespace {

// A tag the calibration uses: id, side and pose in the body frame b.
struct UsedTag {
  int id = 0;
  double size = 0;
  obs::SE3 g_bt = obs::SE3::Identity();
};

// The front end's view of the used tags: one target, the first tag its primary, the others its
// bundle (poses relative to the primary), so that every tag is decided by run's rules.
io::TargetConfig detector_body(const std::string& family, const std::vector<UsedTag>& tags) {
  io::TargetConfig t;
  t.family = family;
  t.id = tags[0].id;
  t.size = tags[0].size;
  for (size_t k = 1; k < tags.size(); ++k)
    t.bundle.push_back({tags[k].id, tags[k].size, tags[0].g_bt.inverse() * tags[k].g_bt});
  return t;
}

bool is_static(const sources::Dataset& ds, size_t i) {
  const auto& poses = ds.cameras[i].poses;
  const obs::SE3& g = ds.network.cameras[i].g_wi;
  for (const auto& p : poses)
    if (!p.isApprox(g, 1e-9)) return false;
  return true;
}

// Every camera's frames through the front end: the used tags seen, per camera. Counts the front
// end's refusals of a used tag (any decision but detected / not_found).
void observe_all(sources::Dataset& ds, const std::vector<UsedTag>& tags, const std::string& family,
                 const CalibrationSettings& s, std::vector<TagSeen>& seen,
                 CalibrationResult& result) {
  const auto body = detector_body(family, tags);
  frontend::DetectorSettings det = s.detector;
  frontend::set_target(det, body);
  frontend::FrontEnd fe(det, s.tracking);
  const int frames = s.max_frames > 0 ? std::min(s.max_frames, ds.frame_count) : ds.frame_count;
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    auto& cr = result.cameras[i];
    const auto t0 = Clock::now();
    frontend::TrackState track;
    const bool moving = !is_static(ds, i);
    cr.moving = moving;
    const int n = std::min(frames, ds.camera_frame_count(i));
    for (int f = 0; f < n; ++f) {
      const cv::Mat img = ds.read(i, f);
      if (img.empty()) continue;
      ++cr.images;
      frontend::FrameDetections all;
      const auto o = fe.observe(img, ds.cameras[i].calib, &all, &track);
      for (const auto& d : all.tags)
        if (d.status != frontend::TargetStatus::detected &&
            d.status != frontend::TargetStatus::not_found)
          ++cr.rejected_front_end;
      if (!o.delta) continue;
      for (size_t a = 0; a < o.slots.size(); ++a) {
        const auto& tag = tags[size_t(o.slots[a])];
        TagSeen t;
        t.cam = i;
        t.frame = f;
        t.tag = tag.id;
        if (moving) t.B_inv = ds.camera_pose(i, f).inverse();
        const auto sq = obs::FeatureModel::square(tag.size);
        for (int k = 0; k < 4; ++k) {
          t.P[size_t(k)] = tag.g_bt * sq.points_o[size_t(k)];
          t.m[size_t(k)] = Eigen::Vector2d(o.f_normalized[long(8 * a + 2 * k)],
                                           o.f_normalized[long(8 * a + 2 * k + 1)]);
        }
        seen.push_back(t);
      }
    }
    cr.seconds += seconds_since(t0);
  }
}

}  // namespace

FrameCorrelation frame_correlation(const std::vector<CameraResult::Residual>& residuals) {
  struct Group {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int n = 0;
  };
  std::map<std::pair<int, int>, Group> groups;  // (tag, corner)
  Eigen::Vector2d total = Eigen::Vector2d::Zero();
  int N = 0;
  for (const auto& r : residuals) {
    if (!r.used) continue;
    auto& g = groups[{r.tag, r.corner}];
    g.sum += Eigen::Vector2d(r.du, r.dv);
    ++g.n;
    total += Eigen::Vector2d(r.du, r.dv);
    ++N;
  }
  FrameCorrelation out;
  const int G = static_cast<int>(groups.size());
  if (G < 2 || N <= G) return out;
  const Eigen::Vector2d mean = total / N;
  double within = 0.0, between = 0.0, sum_n2 = 0.0;
  for (const auto& r : residuals) {
    if (!r.used) continue;
    const auto& g = groups[{r.tag, r.corner}];
    within += (Eigen::Vector2d(r.du, r.dv) - g.sum / g.n).squaredNorm();
  }
  for (const auto& [key, g] : groups) {
    between += g.n * (g.sum / g.n - mean).squaredNorm();
    sum_n2 += double(g.n) * g.n;
  }
  const double msw = within / (2.0 * (N - G)), msb = between / (2.0 * (G - 1));
  const double n0 = (N - sum_n2 / N) / (G - 1);
  const double denominator = msb + (n0 - 1.0) * msw;
  out.rho = denominator > 0 ? std::clamp((msb - msw) / denominator, 0.0, 1.0) : 0.0;
  out.frames = double(N) / G;
  out.inflation = 1.0 + (out.frames - 1.0) * out.rho;
  return out;
}

namespace {

void fill_results(Ba& ba, const std::vector<Mat6>& cov, const std::vector<bool>& cov_ok,
                  double sigma2_common, bool per_camera_sigma, sources::Dataset& ds,
                  CalibrationResult& result) {
  const size_t n = ba.X.size();
  std::vector<double> sum(n, 0.0);
  std::vector<int> corners(n, 0);
  std::vector<std::set<int>> frames(n);
  for (auto& c : result.cameras) c.residuals.clear();
  for (const auto& o : ba.seen) {
    auto& cr = result.cameras[o.cam];
    (o.used ? cr.observations_used : cr.rejected_outlier)++;
    for (int k = 0; k < 4; ++k) {
      const auto r = ba.residual(o, k);
      cr.residuals.push_back({o.frame, o.tag, k, r.x(), r.y(), o.used});
      if (o.used) sum[o.cam] += r.squaredNorm(), ++corners[o.cam];
    }
    if (o.used) frames[o.cam].insert(o.frame);
  }
  for (size_t i = 0; i < n; ++i) {
    auto& cr = result.cameras[i];
    if (!cr.reason.empty()) continue;
    cr.frames_seen = int(frames[i].size());
    cr.rms_px = corners[i] ? std::sqrt(sum[i] / corners[i]) : 0.0;
    cr.X = ba.X[i];
    cr.g_wi0 = cr.moving ? ba.X[i] * ds.camera_pose(i, 0) : ba.X[i];
    if (cr.observations_used == 0) {
      cr.reason = cr.rejected_outlier > 0 ? "all " + std::to_string(cr.rejected_outlier) +
                                                " tag observations rejected as outliers"
                                          : "no usable tag observation";
      continue;
    }
    if (cr.reference) {
      cr.ok = true;
      continue;
    }
    if (!cov_ok[i]) {
      cr.reason = "pose not determined by its observations (rank-deficient covariance)";
      continue;
    }
    // sigma^2 = sum r^2 / (m - n): m residuals (2 per corner), n = 6 parameters (per camera),
    // times the design effect of errors that repeat from frame to frame.
    const double s2 = per_camera_sigma ? sum[i] / std::max(1, 2 * corners[i] - 6) : sigma2_common;
    const FrameCorrelation fc = frame_correlation(cr.residuals);
    cr.frame_correlation = fc.rho;
    cr.covariance_inflation = fc.inflation;
    cr.covariance = cov[i] * s2 * fc.inflation;
    cr.ok = true;
  }
}

std::vector<UsedTag> select_tags(std::vector<UsedTag> all, const std::vector<int>& only,
                                 const std::string& where) {
  if (only.empty()) return all;
  std::vector<UsedTag> out;
  for (int id : only) {
    auto it = std::find_if(all.begin(), all.end(), [&](const UsedTag& t) { return t.id == id; });
    if (it == all.end())
      throw InputError("--tags: tag " + std::to_string(id) + " is not in " + where);
    out.push_back(*it);
  }
  return out;
}

void init_result(sources::Dataset& ds, CalibrationResult& result) {
  result.cameras.clear();
  for (const auto& c : ds.network.cameras) {
    CameraResult cr;
    cr.id = c.id;
    result.cameras.push_back(cr);
  }
}

void fill_calibration_scale(const sources::Dataset& ds, Ba& ba) {
  for (const auto& c : ds.cameras) {
    ba.fx.push_back(c.calib.K(0, 0));
    ba.fy.push_back(c.calib.K(1, 1));
  }
}

CalibrationResult calibrate_with_map(sources::Dataset& ds, const TagMap& map,
                                     const CalibrationSettings& s) {
  CalibrationResult result;
  result.with_map = true;
  init_result(ds, result);
  // A tag of the (first) target moves: taken for a static map tag it would corrupt the poses.
  // Other targets of network.yaml may be static tags (a rendered map's tags are such targets).
  const auto& moving = ds.network.target();
  for (size_t k = 0; k < map.tags.size(); ++k)
    for (size_t j = 0; j < moving.tag_count(); ++j)
      if (moving.family == map.tags[k].family && moving.tag_id(j) == map.tags[k].id)
        throw InputError(map.source + ": tags[" + std::to_string(k) + "].id: tag " +
                         std::to_string(map.tags[k].id) + " is on the target of " +
                         ds.network.source + " (a map lists static tags only)");
  std::vector<UsedTag> all;
  for (const auto& t : map.tags) all.push_back({t.id, t.size, t.g_wt});
  const auto tags = select_tags(all, s.tags, map.source);

  Ba ba;
  const size_t n = ds.cameras.size();
  observe_all(ds, tags, map.tags[0].family, s, ba.seen, result);
  fill_calibration_scale(ds, ba);
  ba.Y = {obs::SE3::Identity()};
  ba.db = {{0, 0, 0, 0, 0, 0}};
  ba.body_fixed = {true};
  ba.X.assign(n, obs::SE3::Identity());
  ba.dc.assign(n, {0, 0, 0, 0, 0, 0});
  ba.cam_fixed.assign(n, true);
  const auto images = by_image(ba);
  for (size_t i = 0; i < n; ++i) {
    auto& cr = result.cameras[i];
    const auto t0 = Clock::now();
    std::vector<obs::SE3> candidates, naive;
    for (const auto& [key, group] : images) {
      if (key.first != i) continue;
      const obs::SE3 B_inv = group[0]->B_inv;
      // g_wi(t) = X B(t) = g_bi: X = g_ib^-1 B(t)^-1.
      if (auto g = image_pnp(group)) candidates.push_back(g->inverse() * B_inv);
      if (auto g = naive_pnp(group)) naive.push_back(g->inverse() * B_inv);
    }
    if (!naive.empty()) cr.naive_pnp = mean_pose(naive);
    if (candidates.empty()) {
      cr.reason = "no map tag seen in " + std::to_string(cr.images) + " images" +
                  (cr.rejected_front_end
                       ? " (" + std::to_string(cr.rejected_front_end) + " refused by the front end)"
                       : "");
      cr.seconds += seconds_since(t0);
      continue;
    }
    double best = 1e300;
    for (const auto& X : candidates) {
      const double c = robust_cost(ba, i, X, s.huber_px);
      if (c < best) best = c, ba.X[i] = X;
    }
    cr.seconds += seconds_since(t0);
  }
  // Each camera is its own problem (the map is fixed): solve them one by one, so that each
  // camera's rejection threshold and noise estimate are its own.
  const auto seen_all = ba.seen;
  std::vector<Mat6> cov(n, Mat6::Zero());
  std::vector<bool> cov_ok(n, false);
  for (size_t i = 0; i < n; ++i) {
    if (!result.cameras[i].reason.empty()) continue;
    const auto t0 = Clock::now();
    Ba one = ba;
    one.seen.clear();
    for (const auto& o : seen_all)
      if (o.cam == i) one.seen.push_back(o);
    one.cam_fixed[i] = false;
    solve(one, s);
    std::vector<bool> ok;
    const auto c = camera_covariances(one, ok);
    cov[i] = c[i];
    cov_ok[i] = ok[i];
    ba.X[i] = one.X[i];
    size_t j = 0;
    for (auto& o : ba.seen)
      if (o.cam == i) o.used = one.seen[j++].used;
    result.cameras[i].seconds += seconds_since(t0);
  }
  fill_results(ba, cov, cov_ok, 0.0, true, ds, result);
  return result;
}

// The moments of a moved tag: groups of images of at least two cameras whose times are within
// same_moment_s of the group's first (each moment one pose Y_k of the body).
struct Moments {
  std::map<std::pair<size_t, int>, int> of_image;  ///< (camera, frame) -> moment
  std::vector<std::set<size_t>> cameras;           ///< per moment: the cameras in it
};

Moments group_moments(const sources::Dataset& ds, const std::vector<TagSeen>& seen,
                      double same_moment_s) {
  struct Img {
    double t;
    size_t cam;
    int frame;
  };
  std::vector<Img> imgs;
  {
    std::set<std::pair<size_t, int>> done;
    for (const auto& o : seen)
      if (done.insert({o.cam, o.frame}).second)
        imgs.push_back({ds.frame_time(o.cam, o.frame), o.cam, o.frame});
  }
  std::sort(imgs.begin(), imgs.end(), [](const Img& a, const Img& b) { return a.t < b.t; });
  Moments m;
  for (size_t a = 0; a < imgs.size();) {
    size_t b = a;
    std::set<size_t> cams;
    while (b < imgs.size() && imgs[b].t - imgs[a].t < same_moment_s) cams.insert(imgs[b].cam), ++b;
    if (cams.size() >= 2) {
      for (size_t c = a; c < b; ++c)
        m.of_image[{imgs[c].cam, imgs[c].frame}] = int(m.cameras.size());
      m.cameras.push_back(cams);
    }
    a = b;
  }
  return m;
}

// The cameras linked to camera `ref` through shared moments (a union-find would do as well).
std::vector<bool> linked_cameras(const std::vector<std::set<size_t>>& moment_cams, size_t n,
                                 size_t ref) {
  std::vector<bool> linked(n, false);
  linked[ref] = true;
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& cams : moment_cams) {
      bool any = false;
      for (size_t c : cams) any = any || linked[c];
      if (any)
        for (size_t c : cams)
          if (!linked[c]) linked[c] = grew = true;
    }
  }
  return linked;
}

// Which cameras and moments have an initial pose (initial_poses).
struct Known {
  std::vector<bool> cams, bodies;
};

// Initial poses (ba.X of the cameras `linked` to the reference, ba.Y of the moments): per image
// g_ib from PnP; breadth first from the reference camera `ref` (its X set), each new pose the
// candidate with the smallest robust cost over what is already known.
Known initial_poses(Ba& ba, const std::vector<bool>& linked, size_t ref, double huber_px) {
  const auto images = by_image(ba);
  std::map<std::pair<size_t, size_t>, obs::SE3> g_io;  // (camera, moment) -> g_ib
  for (const auto& [key, group] : images)
    if (auto g = image_pnp(group)) g_io[{key.first, group[0]->body}] = *g;
  const size_t n = ba.X.size();
  std::vector<bool> cam_known(n, false), body_known(ba.Y.size(), false);
  cam_known[ref] = true;
  for (bool grew = true; grew;) {
    grew = false;
    for (size_t k = 0; k < ba.Y.size(); ++k) {
      if (body_known[k]) continue;
      for (const auto& [key, g] : g_io)
        if (key.second == k && cam_known[key.first]) {
          // Y_k = g_wb = X B(t) g_ib.
          const size_t cam = key.first;  // structured bindings are not captured before C++20
          const auto& o = *std::find_if(ba.seen.begin(), ba.seen.end(), [&](const TagSeen& t) {
            return t.cam == cam && t.body == k;
          });
          ba.Y[k] = ba.X[key.first] * o.B_inv.inverse() * g;
          body_known[k] = grew = true;
          break;
        }
    }
    for (size_t i = 0; i < n; ++i) {
      if (cam_known[i] || !linked[i]) continue;
      std::vector<obs::SE3> cands;
      for (const auto& [key, g] : g_io)
        if (key.first == i && body_known[key.second]) {
          const size_t body = key.second;  // structured bindings are not captured before C++20
          const auto& o = *std::find_if(ba.seen.begin(), ba.seen.end(), [&](const TagSeen& t) {
            return t.cam == i && t.body == body;
          });
          cands.push_back(ba.Y[key.second] * g.inverse() * o.B_inv);  // X = Y g_ib^-1 B^-1
        }
      double best = 1e300;
      for (const auto& X : cands) {
        const double c = robust_cost(ba, i, X, huber_px, &body_known);
        if (c < best) best = c, ba.X[i] = X;
      }
      if (!cands.empty()) cam_known[i] = grew = true;
    }
  }
  return {cam_known, body_known};
}

// sigma^2 = sum r^2 / (m - n) over the used observations: m residuals (2 per corner), n free
// parameters (6 per moment and per camera used, less the reference's); 0 when m <= n.
double residual_variance(const Ba& ba) {
  double sum = 0;
  int m = 0;
  std::set<size_t> cams_used, bodies_used;
  for (const auto& o : ba.seen)
    if (o.used) {
      for (int k = 0; k < 4; ++k) sum += ba.residual(o, k).squaredNorm(), m += 2;
      cams_used.insert(o.cam);
      bodies_used.insert(o.body);
    }
  const int params = 6 * int(bodies_used.size() + cams_used.size() - 1);
  return m > params ? sum / (m - params) : 0.0;
}

CalibrationResult calibrate_without_map(sources::Dataset& ds, const CalibrationSettings& s) {
  CalibrationResult result;
  init_result(ds, result);
  const auto& target = ds.network.target();
  std::vector<UsedTag> all;
  for (size_t k = 0; k < target.tag_count(); ++k)
    all.push_back({target.tag_id(k), target.tag_size(k), target.tag_pose(k)});
  const auto tags = select_tags(all, s.tags, ds.network.source + " (target and its bundle)");
  const size_t n = ds.cameras.size();
  const int ref = s.reference_camera != 0 ? ds.index_of(s.reference_camera) : 0;
  std::vector<TagSeen> seen;
  observe_all(ds, tags, target.family, s, seen, result);

  const Moments moments = group_moments(ds, seen, s.same_moment_s);
  const auto& moment_of = moments.of_image;
  const auto& moment_cams = moments.cameras;
  const std::vector<bool> linked = linked_cameras(moment_cams, n, size_t(ref));
  std::vector<int> seen_count(n, 0);
  for (const auto& o : seen) ++seen_count[o.cam];
  for (size_t i = 0; i < n; ++i) {
    auto& cr = result.cameras[i];
    if (seen_count[i] == 0)
      cr.reason = "no tag of the moved body seen in " + std::to_string(cr.images) + " images";
    else if (!linked[i])
      cr.reason = "never shares a moment (timestamps.csv) with camera " +
                  std::to_string(ds.network.cameras[size_t(ref)].id) +
                  " or a camera linked to it: its pose cannot be related to the others";
  }
  if (!result.cameras[size_t(ref)].reason.empty())
    throw InputError("--reference-camera: camera " +
                     std::to_string(ds.network.cameras[size_t(ref)].id) + ": " +
                     result.cameras[size_t(ref)].reason);

  Ba ba;
  fill_calibration_scale(ds, ba);
  for (auto& o : seen) {
    auto it = moment_of.find({o.cam, o.frame});
    if (it == moment_of.end() || !linked[o.cam]) continue;
    o.body = size_t(it->second);
    ba.seen.push_back(o);
  }
  result.moments = int(moment_cams.size());
  ba.X.assign(n, obs::SE3::Identity());
  ba.dc.assign(n, {0, 0, 0, 0, 0, 0});
  ba.cam_fixed.assign(n, false);
  ba.Y.assign(moment_cams.size(), obs::SE3::Identity());
  ba.db.assign(moment_cams.size(), {0, 0, 0, 0, 0, 0});
  ba.body_fixed.assign(moment_cams.size(), false);
  // The gauge: the reference's X (static: g_wi; moving: the registration of its believed poses).
  const bool ref_moving = !is_static(ds, size_t(ref));
  if (s.reference_from_network)
    ba.X[size_t(ref)] = ref_moving ? obs::SE3::Identity() : ds.network.cameras[size_t(ref)].g_wi;
  else
    ba.X[size_t(ref)] =
        ref_moving ? ds.camera_pose(size_t(ref), 0).inverse() : obs::SE3::Identity();
  ba.cam_fixed[size_t(ref)] = true;
  result.cameras[size_t(ref)].reference = true;

  const Known known = initial_poses(ba, linked, size_t(ref), s.huber_px);
  const auto& cam_known = known.cams;
  const auto& body_known = known.bodies;
  for (size_t i = 0; i < n; ++i)
    if (linked[i] && !cam_known[i] && result.cameras[i].reason.empty())
      result.cameras[i].reason = "no PnP pose of the body in its shared moments";
  // Observations of cameras or moments without an initial pose stay out.
  for (auto& o : ba.seen)
    if (!cam_known[o.cam] || !body_known[o.body]) o.used = false;
  const auto t0 = Clock::now();
  solve(ba, s);
  std::vector<bool> cov_ok;
  const auto cov = camera_covariances(ba, cov_ok);
  const double s2 = residual_variance(ba);
  result.sigma_px = std::sqrt(s2);
  const double solve_s = seconds_since(t0);
  for (auto& c : result.cameras) c.seconds += solve_s / double(n);
  fill_results(ba, cov, cov_ok, s2, false, ds, result);
  return result;
}

}  // namespace

CalibrationResult calibrate(sources::Dataset& ds, const std::optional<TagMap>& map,
                            const CalibrationSettings& s) {
  if (!(s.huber_px > 0) || !(s.reject_sigmas > 0) || !(s.reject_min_px > 0) || s.max_rounds < 1 ||
      !(s.same_moment_s > 0))
    throw InputError(
        "calibration settings: huber_px, reject_sigmas, reject_min_px, same_moment_s must be > 0 "
        "and max_rounds >= 1");
  if (s.reference_camera != 0 && ds.index_of(s.reference_camera) < 0)
    throw InputError("--reference-camera: camera " + std::to_string(s.reference_camera) +
                     " is not listed under cameras in " + ds.network.source);
  return map ? calibrate_with_map(ds, *map, s) : calibrate_without_map(ds, s);
}

io::NetworkConfig calibrated_network(const io::NetworkConfig& net, const CalibrationResult& r,
                                     bool keep_going) {
  io::NetworkConfig out = net;
  out.cameras.clear();
  std::set<int> dropped;
  std::string names;
  for (size_t i = 0; i < net.cameras.size(); ++i) {
    const auto& c = r.cameras.at(i);
    if (c.ok) {
      auto cam = net.cameras[i];
      cam.g_wi = c.g_wi0;
      out.cameras.push_back(cam);
    } else {
      dropped.insert(c.id);
      names += (names.empty() ? "" : ", ") + std::to_string(c.id);
    }
  }
  if (!dropped.empty() && !keep_going)
    throw InputError("camera" + std::string(dropped.size() > 1 ? "s " : " ") + names +
                     " could not be calibrated (see above); --keep-going leaves " +
                     (dropped.size() > 1 ? "them" : "it") + " out of network.yaml");
  if (out.cameras.empty()) throw InputError("no camera could be calibrated");
  out.edges.clear();
  for (const auto& e : net.edges)
    if (!dropped.count(e.first) && !dropped.count(e.second)) out.edges.push_back(e);
  return out;
}

}  // namespace netvmo::calib
