// `netvmo calibrate`: camera poses from tags, by bundle adjustment over corners with Ceres
// (calibrate.hpp has the model and docs/calibration.md the derivations).
#include "netvmo/pipeline/calib/calibrate.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <set>
#include <sstream>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"
#include "netvmo/pipeline/io/truth_io.hpp"

namespace netvmo::calib {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A pose and its perturbation (calibrate.hpp): (R exp(hat(dtheta)), p + dp), delta = [dp; dtheta].
obs::SE3 perturbed(const obs::SE3& g, const double* d) {
  obs::SE3 out = g;
  out.linear() = g.linear() * obs::exp_so3(obs::Vec3(d[3], d[4], d[5]));
  out.translation() = g.translation() + obs::Vec3(d[0], d[1], d[2]);
  return out;
}

// One tag seen in one image: its 4 corners (undistorted normalized) and its corner points in the
// body frame b (the world for a map; the moved body's frame o otherwise).
struct TagSeen {
  size_t cam = 0;
  int frame = 0;
  size_t body = 0;  // moment index (no-map case); 0 for a map
  int tag = 0;
  obs::SE3 B_inv = obs::SE3::Identity();  // B_i(t)^-1 (identity for a static camera)
  std::array<obs::Vec3, 4> P;
  std::array<Eigen::Vector2d, 4> m;
  bool used = true;
};

// Reprojection residual of one corner (eq:visual_mea with lambda = 1, scaled by fx, fy to
// undistorted pixels): f(g_io P) - measured, g_io = B^-1 X(dc)^-1 Y(db), X and Y perturbed as in
// the header.
struct CornerCost {
  obs::Vec3 P;
  Eigen::Vector2d m;
  obs::Mat3 RX, RY, RB;  // RB, pB: B (not its inverse)
  obs::Vec3 pX, pY, pB;
  double fx = 1, fy = 1;

  template <typename T>
  bool operator()(const T* c, const T* b, T* r) const {
    const T Pb[3] = {T(P.x()), T(P.y()), T(P.z())};
    T q[3];
    ceres::AngleAxisRotatePoint(b + 3, Pb, q);
    T w[3], d[3], e[3], f[3], g[3];
    for (int i = 0; i < 3; ++i)
      w[i] = T(RY(i, 0)) * q[0] + T(RY(i, 1)) * q[1] + T(RY(i, 2)) * q[2] + T(pY(i)) + b[i];
    for (int i = 0; i < 3; ++i) d[i] = w[i] - T(pX(i)) - c[i];
    for (int i = 0; i < 3; ++i) e[i] = T(RX(0, i)) * d[0] + T(RX(1, i)) * d[1] + T(RX(2, i)) * d[2];
    const T minus[3] = {-c[3], -c[4], -c[5]};
    ceres::AngleAxisRotatePoint(minus, e, f);
    for (int i = 0; i < 3; ++i) f[i] -= T(pB(i));
    for (int i = 0; i < 3; ++i) g[i] = T(RB(0, i)) * f[0] + T(RB(1, i)) * f[1] + T(RB(2, i)) * f[2];
    if (!(g[2] > T(1e-9))) return false;
    r[0] = T(fx) * (g[0] / g[2] - T(m.x()));
    r[1] = T(fy) * (g[1] / g[2] - T(m.y()));
    return true;
  }
};

// The least-squares problem over cameras X_i and bodies Y_k (a map: one fixed body, the world).
struct Ba {
  std::vector<obs::SE3> X, Y;
  std::vector<std::array<double, 6>> dc, db;
  std::vector<bool> cam_fixed, body_fixed;
  std::vector<TagSeen> seen;
  std::vector<double> fx, fy;  // per camera

  // Corner k of observation o's residual [undistorted px] at the current poses (plus deltas).
  Eigen::Vector2d residual(const TagSeen& o, int k, const obs::SE3* X_alt = nullptr) const {
    const obs::SE3 Xc = X_alt ? *X_alt : perturbed(X[o.cam], dc[o.cam].data());
    const obs::SE3 Yb = perturbed(Y[o.body], db[o.body].data());
    const obs::Vec3 pc = o.B_inv * (Xc.inverse() * (Yb * o.P[size_t(k)]));
    if (!(pc.z() > 1e-9)) return Eigen::Vector2d(1e6, 1e6);
    return Eigen::Vector2d(fx[o.cam] * (pc.x() / pc.z() - o.m[size_t(k)].x()),
                           fy[o.cam] * (pc.y() / pc.z() - o.m[size_t(k)].y()));
  }

  CornerCost cost(const TagSeen& o, int k) const {
    CornerCost c;
    c.P = o.P[size_t(k)];
    c.m = o.m[size_t(k)];
    c.RX = X[o.cam].linear();
    c.pX = X[o.cam].translation();
    c.RY = Y[o.body].linear();
    c.pY = Y[o.body].translation();
    const obs::SE3 B = o.B_inv.inverse();
    c.RB = B.linear();
    c.pB = B.translation();
    c.fx = fx[o.cam];
    c.fy = fy[o.cam];
    return c;
  }

  // Builds the Ceres problem over the used observations (loss: Huber of `huber_px`, or none).
  void build(ceres::Problem& p, double huber_px) {
    for (const auto& o : seen) {
      if (!o.used) continue;
      for (int k = 0; k < 4; ++k) {
        auto* f = new ceres::AutoDiffCostFunction<CornerCost, 2, 6, 6>(new CornerCost(cost(o, k)));
        p.AddResidualBlock(f, huber_px > 0 ? new ceres::HuberLoss(huber_px) : nullptr,
                           dc[o.cam].data(), db[o.body].data());
      }
    }
    for (size_t i = 0; i < X.size(); ++i)
      if (p.HasParameterBlock(dc[i].data()) && cam_fixed[i])
        p.SetParameterBlockConstant(dc[i].data());
    for (size_t k = 0; k < Y.size(); ++k)
      if (p.HasParameterBlock(db[k].data()) && body_fixed[k])
        p.SetParameterBlockConstant(db[k].data());
  }
  // Folds the deltas into the poses.
  void fold() {
    for (size_t i = 0; i < X.size(); ++i) X[i] = perturbed(X[i], dc[i].data()), dc[i].fill(0.0);
    for (size_t k = 0; k < Y.size(); ++k) Y[k] = perturbed(Y[k], db[k].data()), db[k].fill(0.0);
  }
};

// Solve / reject rounds (header: reject_sigmas, reject_min_px, max_rounds). `group` selects the
// observations whose RMS sets the rejection threshold: per camera for a map (each camera its own
// problem), all together otherwise.
void solve(Ba& ba, const CalibrationSettings& s) {
  for (int round = 0; round < s.max_rounds; ++round) {
    ceres::Problem problem;
    ba.build(problem, s.huber_px);
    if (problem.NumResidualBlocks() == 0) return;
    ceres::Solver::Options opt;
    opt.linear_solver_type = ba.Y.size() > 1 ? ceres::SPARSE_SCHUR : ceres::DENSE_QR;
    opt.max_num_iterations = 100;
    opt.num_threads = 1;
    opt.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(opt, &problem, &summary);
    ba.fold();
    double sum = 0;
    int n = 0;
    for (const auto& o : ba.seen)
      if (o.used)
        for (int k = 0; k < 4; ++k) sum += ba.residual(o, k).squaredNorm(), ++n;
    const double rms = std::sqrt(sum / std::max(n, 1));
    const double limit = std::max(s.reject_sigmas * rms, s.reject_min_px);
    bool changed = false;
    for (auto& o : ba.seen) {
      if (!o.used) continue;
      for (int k = 0; k < 4; ++k)
        if (ba.residual(o, k).norm() > limit) {
          o.used = false;
          changed = true;
          break;
        }
    }
    if (!changed) return;
  }
}

// Ceres' covariance of the free camera blocks, unit corner noise: (J^T J)^-1 over the used
// observations without the loss (the outliers are gone; Huber's weight is 1 on the inliers).
std::vector<Mat6> camera_covariances(Ba& ba, std::vector<bool>& ok) {
  ceres::Problem problem;
  ba.build(problem, 0.0);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (size_t i = 0; i < ba.X.size(); ++i)
    if (!ba.cam_fixed[i] && problem.HasParameterBlock(ba.dc[i].data()))
      blocks.emplace_back(ba.dc[i].data(), ba.dc[i].data());
  std::vector<Mat6> out(ba.X.size(), Mat6::Zero());
  ok.assign(ba.X.size(), false);
  if (blocks.empty()) return out;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;  // small problems; reports rank deficiency
  co.null_space_rank = 0;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  if (!cov.Compute(blocks, &problem)) return out;
  for (size_t i = 0; i < ba.X.size(); ++i) {
    if (ba.cam_fixed[i] || !problem.HasParameterBlock(ba.dc[i].data())) continue;
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> c;
    if (cov.GetCovarianceBlock(ba.dc[i].data(), ba.dc[i].data(), c.data())) {
      out[i] = c;
      ok[i] = true;
    }
  }
  return out;
}

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

// PnP (frontend::pnp_pose) of the points of `obs` (one image's tags): g_ib, pose of the body
// frame in the camera.
std::optional<obs::SE3> image_pnp(const std::vector<const TagSeen*>& obs) {
  obs::FeatureModel m;
  Eigen::VectorXd f(8 * long(obs.size()));
  long j = 0;
  for (const auto* o : obs)
    for (int k = 0; k < 4; ++k) {
      m.points_o.push_back(o->P[size_t(k)]);
      f[j++] = o->m[size_t(k)].x();
      f[j++] = o->m[size_t(k)].y();
    }
  const auto r = frontend::pnp_pose(f, m);
  if (!r) return std::nullopt;
  return r->g_io;
}

// The naive per-frame pose: OpenCV solvePnP (SQPNP) on one image's corners, g_ib.
std::optional<obs::SE3> naive_pnp(const std::vector<const TagSeen*>& obs) {
  std::vector<cv::Point3d> P;
  std::vector<cv::Point2d> m;
  for (const auto* o : obs)
    for (int k = 0; k < 4; ++k) {
      P.emplace_back(o->P[size_t(k)].x(), o->P[size_t(k)].y(), o->P[size_t(k)].z());
      m.emplace_back(o->m[size_t(k)].x(), o->m[size_t(k)].y());
    }
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(P, m, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                    cv::SOLVEPNP_SQPNP))
    return std::nullopt;
  return obs::make_pose(obs::Vec3(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)),
                        obs::Vec3(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)));
}

// The chordal mean of poses: mean position, rotation the closest to the mean matrix.
obs::SE3 mean_pose(const std::vector<obs::SE3>& g) {
  obs::Mat3 R = obs::Mat3::Zero();
  obs::Vec3 p = obs::Vec3::Zero();
  for (const auto& x : g) R += x.linear(), p += x.translation();
  obs::SE3 out = obs::SE3::Identity();
  out.linear() = obs::project_to_so3(R / double(g.size()));
  out.translation() = p / double(g.size());
  return out;
}

// Huber cost of camera i's observations (bodies at their current poses) with pose X_i = X.
double robust_cost(const Ba& ba, size_t i, const obs::SE3& X, double huber,
                   const std::vector<bool>* body_known = nullptr) {
  double c = 0;
  for (const auto& o : ba.seen) {
    if (o.cam != i || (body_known && !(*body_known)[o.body])) continue;
    for (int k = 0; k < 4; ++k) {
      const double r = ba.residual(o, k, &X).norm();
      c += r <= huber ? r * r : 2 * huber * r - huber * huber;
    }
  }
  return c;
}

// Per-image groups of a camera's observations (frame -> observations), in frame order.
std::map<std::pair<size_t, int>, std::vector<const TagSeen*>> by_image(const Ba& ba) {
  std::map<std::pair<size_t, int>, std::vector<const TagSeen*>> g;
  for (const auto& o : ba.seen) g[{o.cam, o.frame}].push_back(&o);
  return g;
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

  // Moments: image times within same_moment_s of a group's first.
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
  std::map<std::pair<size_t, int>, int> moment_of;
  std::vector<std::set<size_t>> moment_cams;
  for (size_t a = 0; a < imgs.size();) {
    size_t b = a;
    std::set<size_t> cams;
    while (b < imgs.size() && imgs[b].t - imgs[a].t < s.same_moment_s)
      cams.insert(imgs[b].cam), ++b;
    if (cams.size() >= 2) {
      for (size_t c = a; c < b; ++c)
        moment_of[{imgs[c].cam, imgs[c].frame}] = int(moment_cams.size());
      moment_cams.push_back(cams);
    }
    a = b;
  }
  // Cameras linked to the reference through shared moments (a union-find would do as well).
  std::vector<bool> linked(n, false);
  linked[size_t(ref)] = true;
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

  // Initial poses: per image g_ib from PnP; breadth first from the reference, each new pose the
  // candidate with the smallest robust cost over what is already known.
  const auto images = by_image(ba);
  std::map<std::pair<size_t, size_t>, obs::SE3> g_io;  // (camera, moment) -> g_ib
  for (const auto& [key, group] : images)
    if (auto g = image_pnp(group)) g_io[{key.first, group[0]->body}] = *g;
  std::vector<bool> cam_known(n, false), body_known(ba.Y.size(), false);
  cam_known[size_t(ref)] = true;
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
        const double c = robust_cost(ba, i, X, s.huber_px, &body_known);
        if (c < best) best = c, ba.X[i] = X;
      }
      if (!cands.empty()) cam_known[i] = grew = true;
    }
  }
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
  // sigma^2 = sum r^2 / (m - n): m residuals (2 per corner), n free parameters.
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
  const double s2 = m > params ? sum / (m - params) : 0.0;
  result.sigma_px = std::sqrt(s2);
  const double solve_s = seconds_since(t0);
  for (auto& c : result.cameras) c.seconds += solve_s / double(n);
  fill_results(ba, cov, cov_ok, s2, false, ds, result);
  return result;
}

std::vector<double> row(const obs::Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

// Error in the covariance's coordinates (header): [p_est - p_true; log(R_true^T R_est)].
obs::Vec6 pose_error(const obs::SE3& est, const obs::SE3& truth) {
  obs::Vec6 e;
  e.head<3>() = est.translation() - truth.translation();
  e.tail<3>() = obs::log_so3(truth.linear().transpose() * est.linear());
  return e;
}

json error_json(const obs::Vec6& e, const Mat6* cov) {
  json j = {{"error", std::vector<double>(e.data(), e.data() + 6)},
            {"position_mm", 1e3 * e.head<3>().norm()},
            {"orientation_deg", e.tail<3>().norm() * 180.0 / M_PI}};
  if (cov && cov->diagonal().minCoeff() > 0) j["d2"] = e.dot(cov->ldlt().solve(e));
  return j;
}

// On rendered data (truth_cameras.csv): each camera's error against the truth, and for the map
// case the naive per-frame solvePnP average's. Without a map the estimate lives in the frame the
// reference camera fixes: the truth is mapped into it (X_ref X_ref,true^-1), static cameras only.
void truth_errors(sources::Dataset& ds, const CalibrationResult& r, json& cameras) {
  const fs::path file = ds.dir / "truth_cameras.csv";
  if (!fs::exists(file)) return;
  std::map<int, obs::SE3> truth0;
  for (const auto& row : io::read_camera_truth_csv(file))
    if (row.frame <= 0) truth0[row.camera] = row.g_wi;
  // X_true of camera i: g_wi,true(0) B(0)^-1 (static: g_wi,true).
  const auto X_true = [&](size_t i) -> std::optional<obs::SE3> {
    const auto it = truth0.find(r.cameras[i].id);
    if (it == truth0.end()) return std::nullopt;
    return r.cameras[i].moving ? obs::SE3(it->second * ds.camera_pose(i, 0).inverse()) : it->second;
  };
  obs::SE3 frame = obs::SE3::Identity();
  if (!r.with_map) {
    for (size_t i = 0; i < r.cameras.size(); ++i)
      if (r.cameras[i].reference) {
        const auto t = X_true(i);
        if (!t) return;
        frame = r.cameras[i].X * t->inverse();
      }
  }
  for (size_t i = 0; i < r.cameras.size(); ++i) {
    const auto& c = r.cameras[i];
    const auto t = X_true(i);
    if (!c.ok || !t || (!r.with_map && c.moving)) continue;
    const obs::SE3 truth = frame * *t;
    cameras[i]["vs_truth"] =
        error_json(pose_error(c.X, truth), c.reference ? nullptr : &c.covariance);
    if (c.naive_pnp)
      cameras[i]["naive_pnp"]["vs_truth"] = error_json(pose_error(*c.naive_pnp, truth), nullptr);
  }
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

void write_calibration(const fs::path& dir, sources::Dataset& ds, const CalibrationResult& r,
                       const io::NetworkConfig& calibrated) {
  io::write_file_atomic(dir / "network.yaml", io::network_yaml(calibrated));
  json j;
  j["case"] = r.with_map ? "map" : "moved_tag";
  j["perturbation"] =
      "X = (R exp(hat(dtheta)), p + dp); covariance of [dp (world, m); dtheta (camera frame, rad)]";
  if (!r.with_map) {
    j["sigma_px"] = r.sigma_px;
    j["moments"] = r.moments;
  }
  j["cameras"] = json::array();
  for (const auto& c : r.cameras) {
    json cj;
    cj["id"] = c.id;
    cj["ok"] = c.ok;
    if (!c.reason.empty()) cj["reason"] = c.reason;
    cj["moving"] = c.moving;
    if (c.reference) cj["reference"] = true;
    cj["images"] = c.images;
    cj["frames_seen"] = c.frames_seen;
    cj["observations"] = {{"used", c.observations_used},
                          {"rejected_front_end", c.rejected_front_end},
                          {"rejected_outlier", c.rejected_outlier}};
    cj["seconds"] = c.seconds;
    if (c.ok) {
      cj["p_wi"] = row(c.g_wi0.translation());
      cj["r_wi"] = row(obs::log_so3(c.g_wi0.linear()));
      if (c.moving) {
        cj["X"] = {{"p", row(c.X.translation())}, {"r", row(obs::log_so3(c.X.linear()))}};
      }
      cj["rms_px"] = c.rms_px;
      cj["frame_correlation"] = c.frame_correlation;
      cj["covariance_inflation"] = c.covariance_inflation;
      const obs::Vec6 sd = c.sigmas();
      cj["sigma"] = {{"p_m", row(sd.head<3>())}, {"theta_rad", row(sd.tail<3>())}};
      json cov = json::array();
      for (int a = 0; a < 6; ++a) {
        std::vector<double> rr;
        for (int b = 0; b < 6; ++b) rr.push_back(c.covariance(a, b));
        cov.push_back(rr);
      }
      cj["covariance"] = cov;
    }
    if (c.naive_pnp)
      cj["naive_pnp"] = {{"p_wi", row(c.naive_pnp->translation())},
                         {"r_wi", row(obs::log_so3(c.naive_pnp->linear()))}};
    j["cameras"].push_back(cj);
  }
  truth_errors(ds, r, j["cameras"]);
  io::write_file_atomic(dir / "calibration.json", j.dump(2) + "\n");
  for (const auto& c : r.cameras) {
    std::ostringstream csv;
    csv << "frame,tag,corner,du,dv,used\n";
    csv.precision(9);
    for (const auto& e : c.residuals)
      csv << e.frame << "," << e.tag << "," << e.corner << "," << e.du << "," << e.dv << ","
          << (e.used ? 1 : 0) << "\n";
    io::write_file_atomic(dir / ("residuals_cam_" + std::to_string(c.id) + ".csv"), csv.str());
  }
  // cameras.csv overrides network.yaml's poses in a dataset: when the input has one, so does
  // the output (every kept camera, every frame: X B(t), a static camera its pose).
  bool any_rows = false;
  for (const auto& c : ds.cameras) any_rows = any_rows || !c.poses.empty();
  if (any_rows) {
    std::ostringstream csv;
    csv << io::kCameraPosesHeader << "\n";
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
      const auto& c = r.cameras[i];
      if (!c.ok || calibrated.index_of(c.id) < 0) continue;
      for (int f = 0; f < ds.camera_frame_count(i); ++f) {
        const obs::SE3 g = c.moving ? obs::SE3(c.X * ds.camera_pose(i, f)) : c.X;
        csv << io::format_camera_pose_row(c.id, f, ds.frame_time(i, f), g) << "\n";
      }
    }
    io::write_file_atomic(dir / "cameras.csv", csv.str());
  }
  // timestamps.csv names cameras too: a camera left out (--keep-going) must leave it as well.
  bool any_times = false;
  for (const auto& c : ds.cameras) any_times = any_times || !c.times.empty();
  if (any_times && calibrated.cameras.size() < ds.cameras.size()) {
    std::ostringstream csv;
    csv << io::kTimestampsHeader << "\n";
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
      if (calibrated.index_of(r.cameras[i].id) < 0) continue;
      for (int f = 0; f < ds.camera_frame_count(i); ++f)
        if (const auto t = ds.listed_time(i, f))
          csv << io::format_timestamp_row(r.cameras[i].id, f, *t) << "\n";
    }
    io::write_file_atomic(dir / "timestamps.csv", csv.str());
  }
}

std::string camera_line(const CameraResult& c) {
  char b[512];
  if (!c.ok) {
    std::snprintf(b, sizeof b, "camera %d: not calibrated: %s", c.id, c.reason.c_str());
    return b;
  }
  const obs::Vec3 p = c.g_wi0.translation(), r = obs::log_so3(c.g_wi0.linear());
  const obs::Vec6 sd = c.sigmas();
  std::snprintf(b, sizeof b,
                "camera %d: p_wi [%.4f, %.4f, %.4f] r_wi [%.4f, %.4f, %.4f]%s, %d tag "
                "observations in %d of %d images (%d refused by the front end, %d outliers), "
                "RMS %.3f px, sd %.2f mm / %.3f deg%s",
                c.id, p.x(), p.y(), p.z(), r.x(), r.y(), r.z(), c.moving ? " (at frame 0)" : "",
                c.observations_used, c.frames_seen, c.images, c.rejected_front_end,
                c.rejected_outlier, c.rms_px, 1e3 * sd.head<3>().norm(),
                sd.tail<3>().norm() * 180.0 / M_PI, c.reference ? " (reference: held fixed)" : "");
  return b;
}

}  // namespace netvmo::calib
