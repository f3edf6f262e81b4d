// The calibration's bundle adjustment with Ceres (bundle_adjustment.hpp).
#include "bundle_adjustment.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include "netvmo/pipeline/frontend/pnp.hpp"

namespace netvmo::calib::detail {

obs::SE3 perturbed(const obs::SE3& g, const double* delta) {
  obs::SE3 out = g;
  out.linear() = g.linear() * obs::exp_so3(obs::Vec3(delta[3], delta[4], delta[5]));
  out.translation() = g.translation() + obs::Vec3(delta[0], delta[1], delta[2]);
  return out;
}

Eigen::Vector2d Ba::residual(const TagSeen& o, int k, const obs::SE3* X_alt) const {
  const obs::SE3 Xc = X_alt ? *X_alt : perturbed(X[o.cam], dc[o.cam].data());
  const obs::SE3 Yb = perturbed(Y[o.body], db[o.body].data());
  const obs::Vec3 pc = o.B_inv * (Xc.inverse() * (Yb * o.P[size_t(k)]));
  if (!(pc.z() > 1e-9)) return Eigen::Vector2d(1e6, 1e6);
  return Eigen::Vector2d(fx[o.cam] * (pc.x() / pc.z() - o.m[size_t(k)].x()),
                         fy[o.cam] * (pc.y() / pc.z() - o.m[size_t(k)].y()));
}

void Ba::fold() {
  for (size_t i = 0; i < X.size(); ++i) X[i] = perturbed(X[i], dc[i].data()), dc[i].fill(0.0);
  for (size_t k = 0; k < Y.size(); ++k) Y[k] = perturbed(Y[k], db[k].data()), db[k].fill(0.0);
}

namespace {

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

// Corner k of observation o as Ceres' cost at the current poses.
CornerCost corner_cost(const Ba& ba, const TagSeen& o, int k) {
  CornerCost c;
  c.P = o.P[size_t(k)];
  c.m = o.m[size_t(k)];
  c.RX = ba.X[o.cam].linear();
  c.pX = ba.X[o.cam].translation();
  c.RY = ba.Y[o.body].linear();
  c.pY = ba.Y[o.body].translation();
  const obs::SE3 B = o.B_inv.inverse();
  c.RB = B.linear();
  c.pB = B.translation();
  c.fx = ba.fx[o.cam];
  c.fy = ba.fy[o.cam];
  return c;
}

// Builds the Ceres problem over the used observations (loss: Huber of `huber_px`, or none).
void build(Ba& ba, ceres::Problem& p, double huber_px) {
  for (const auto& o : ba.seen) {
    if (!o.used) continue;
    for (int k = 0; k < 4; ++k) {
      auto* f = new ceres::AutoDiffCostFunction<CornerCost, 2, 6, 6>(
          new CornerCost(corner_cost(ba, o, k)));
      p.AddResidualBlock(f, huber_px > 0 ? new ceres::HuberLoss(huber_px) : nullptr,
                         ba.dc[o.cam].data(), ba.db[o.body].data());
    }
  }
  for (size_t i = 0; i < ba.X.size(); ++i)
    if (p.HasParameterBlock(ba.dc[i].data()) && ba.cam_fixed[i])
      p.SetParameterBlockConstant(ba.dc[i].data());
  for (size_t k = 0; k < ba.Y.size(); ++k)
    if (p.HasParameterBlock(ba.db[k].data()) && ba.body_fixed[k])
      p.SetParameterBlockConstant(ba.db[k].data());
}

}  // namespace

void solve(Ba& ba, const CalibrationSettings& s) {
  for (int round = 0; round < s.max_rounds; ++round) {
    ceres::Problem problem;
    build(ba, problem, s.huber_px);
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

std::vector<Mat6> camera_covariances(Ba& ba, std::vector<bool>& ok) {
  ceres::Problem problem;
  build(ba, problem, 0.0);
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

double robust_cost(const Ba& ba, size_t i, const obs::SE3& X, double huber,
                   const std::vector<bool>* body_known) {
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

std::map<std::pair<size_t, int>, std::vector<const TagSeen*>> by_image(const Ba& ba) {
  std::map<std::pair<size_t, int>, std::vector<const TagSeen*>> g;
  for (const auto& o : ba.seen) g[{o.cam, o.frame}].push_back(&o);
  return g;
}

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

obs::SE3 mean_pose(const std::vector<obs::SE3>& g) {
  obs::Mat3 R = obs::Mat3::Zero();
  obs::Vec3 p = obs::Vec3::Zero();
  for (const auto& x : g) R += x.linear(), p += x.translation();
  obs::SE3 out = obs::SE3::Identity();
  out.linear() = obs::project_to_so3(R / double(g.size()));
  out.translation() = p / double(g.size());
  return out;
}

}  // namespace netvmo::calib::detail
