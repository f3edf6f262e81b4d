// The measurement's covariance: the corners' from the edge fits (refine_corners), taken to
// normalized coordinates (Observation::f_covariance), and the PnP pose's through the
// projections' Jacobian (pnp_covariance). The Jacobian against finite differences, the sandwich
// against its closed form, and both covariances against the empirical spread of the corners and
// poses over seeded sensor noise on synthesized pictures (coverage of the 95 % ellipsoids).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <vector>

#include "netvmo/observer/jacobian.hpp"
#include "netvmo/pipeline/frontend/front_end.hpp"
#include "netvmo/pipeline/frontend/pnp.hpp"
#include "synth.hpp"

namespace netvmo {
namespace {
using frontend::PoseCovariance;
using testing::facing_pose;

// The pose perturbed as PoseCovariance says: p + dp, exp(hat(dphi)) R.
obs::SE3 perturbed(const obs::SE3& g, const Eigen::Matrix<double, 6, 1>& d) {
  obs::SE3 out = g;
  out.translation() += d.head<3>();
  out.linear() = obs::exp_so3(d.tail<3>()) * g.linear();
  return out;
}

// (dp, dphi) of b relative to a, PoseCovariance's convention.
Eigen::Matrix<double, 6, 1> difference(const obs::SE3& b, const obs::SE3& a) {
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = b.translation() - a.translation();
  d.tail<3>() = obs::log_so3(b.linear() * a.linear().transpose());
  return d;
}

TEST(MeasurementCovariance, PnpJacobianIsTheFiniteDifferenceOfTheProjections) {
  const auto model = obs::FeatureModel::square(0.2);
  for (const auto& g : {facing_pose(2.0, 0.1, -0.2, {0.3, 0.2, 0.5}),
                        facing_pose(0.8, -0.3, 0.1, {-0.8, 0.4, -2.0})}) {
    const Eigen::MatrixXd A = frontend::pnp_jacobian(g, model.points_o);
    const double h = 1e-6;
    for (int c = 0; c < 6; ++c) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      d(c) = h;
      const Eigen::VectorXd numeric =
          (obs::project(perturbed(g, d), model) - obs::project(perturbed(g, -d), model)) / (2 * h);
      EXPECT_LT((numeric - A.col(c)).norm(), 1e-7 * (1.0 + A.col(c).norm())) << "column " << c;
    }
  }
}

TEST(MeasurementCovariance, PnpCovarianceOfIsotropicNoiseIsTheInverseInformation) {
  const auto model = obs::FeatureModel::square(0.2);
  const obs::SE3 g = facing_pose(1.5, 0.2, 0.1, {0.4, -0.3, 0.2});
  const double sigma = 0.3 / 610.0;  // 0.3 px at f = 610
  const Eigen::MatrixXd A = frontend::pnp_jacobian(g, model.points_o);
  const PoseCovariance expected = sigma * sigma * (A.transpose() * A).inverse();
  const PoseCovariance C =
      frontend::pnp_covariance(g, model.points_o, sigma * sigma * Eigen::MatrixXd::Identity(8, 8));
  EXPECT_LT((C - expected).norm(), 1e-9 * expected.norm());
  // A correlated f_cov: the sandwich, not the inverse information.
  Eigen::MatrixXd F = sigma * sigma * Eigen::MatrixXd::Identity(8, 8);
  F(0, 2) = F(2, 0) = 0.5 * sigma * sigma;
  const Eigen::MatrixXd B = (A.transpose() * A).inverse() * A.transpose();
  EXPECT_LT((frontend::pnp_covariance(g, model.points_o, F) - B * F * B.transpose()).norm(),
            1e-9 * expected.norm());
  EXPECT_THROW(frontend::pnp_covariance(g, model.points_o, Eigen::MatrixXd::Identity(6, 6)),
               std::invalid_argument);
}

// chi-square quantiles at 0.95
constexpr double kChi2_6 = 12.592, kChi2_8 = 15.507;

struct Spread {
  double corner_coverage = 0, pose_coverage = 0;            // each draw's own covariance
  double corner_coverage_mean = 0, pose_coverage_mean = 0;  // the mean predicted covariance
  double corner_variance_ratio = 0;  // empirical / predicted, mean over the 8 coordinates
  double position_sd_mm = 0, predicted_position_sd_mm = 0;
};

// `draws` pictures of one tag with sensor noise of `noise` gray levels (seeds 1...), blurred by
// 0.8 px: the corners' and PnP poses' spread against their predicted covariances.
Spread spread_over_noise(const io::Calibration& calib, const obs::SE3& g, double noise, int draws) {
  const auto model = obs::FeatureModel::square(0.2);
  frontend::FrontEnd fe;
  std::vector<Eigen::VectorXd> f;
  std::vector<frontend::CornerCovariance> f_cov;
  std::vector<obs::SE3> poses;
  std::vector<PoseCovariance> pose_cov;
  for (int k = 0; k < draws; ++k) {
    testing::SynthSettings opt;
    opt.noise_sigma = noise;
    opt.seed = static_cast<std::uint64_t>(k + 1);
    opt.supersample = 3;
    const cv::Mat img = testing::render_camera_picture(calib, {{0, 0.2, g, {}}}, opt, 0.8);
    const auto o = fe.observe(img, calib);
    if (!o.delta) {
      ADD_FAILURE() << "draw " << k << ": " << o.reason;
      continue;
    }
    EXPECT_EQ(o.f_covariance.size(), 1u);
    const auto pnp = frontend::pnp_pose(o.f_normalized, model);
    if (!pnp) {
      ADD_FAILURE() << "draw " << k << ": no PnP pose";
      continue;
    }
    f.push_back(o.f_normalized);
    f_cov.push_back(o.f_covariance.at(0));
    poses.push_back(pnp->g_io);
    pose_cov.push_back(frontend::pnp_covariance(pnp->g_io, model.points_o, f_cov.back()));
  }
  Spread s;
  const auto n = static_cast<double>(f.size());
  if (f.size() < 10) return s;
  Eigen::VectorXd f_mean = Eigen::VectorXd::Zero(8);
  for (const auto& x : f) f_mean += x / n;
  Eigen::VectorXd var = Eigen::VectorXd::Zero(8), predicted = Eigen::VectorXd::Zero(8);
  // The mean pose: the first pose moved by the mean difference (the spread is small).
  Eigen::Matrix<double, 6, 1> d_mean = Eigen::Matrix<double, 6, 1>::Zero();
  for (const auto& p : poses) d_mean += difference(p, poses[0]) / n;
  const obs::SE3 pose_mean = perturbed(poses[0], d_mean);
  double position_var = 0, predicted_position_var = 0;
  frontend::CornerCovariance f_cov_mean = frontend::CornerCovariance::Zero();
  PoseCovariance pose_cov_mean = PoseCovariance::Zero();
  for (size_t k = 0; k < f.size(); ++k) {
    f_cov_mean += f_cov[k] / n;
    pose_cov_mean += pose_cov[k] / n;
  }
  for (size_t k = 0; k < f.size(); ++k) {
    const Eigen::VectorXd e = f[k] - f_mean;
    var += e.cwiseProduct(e) / (n - 1);
    predicted += f_cov[k].diagonal() / n;
    if (e.dot(f_cov[k].ldlt().solve(e)) <= kChi2_8) s.corner_coverage += 1.0 / n;
    const Eigen::Matrix<double, 6, 1> d = difference(poses[k], pose_mean);
    if (d.dot(pose_cov[k].ldlt().solve(d)) <= kChi2_6) s.pose_coverage += 1.0 / n;
    if (e.dot(f_cov_mean.ldlt().solve(e)) <= kChi2_8) s.corner_coverage_mean += 1.0 / n;
    if (d.dot(pose_cov_mean.ldlt().solve(d)) <= kChi2_6) s.pose_coverage_mean += 1.0 / n;
    position_var += d.head<3>().squaredNorm() / (n - 1);
    predicted_position_var += pose_cov[k].topLeftCorner<3, 3>().trace() / n;
  }
  s.corner_variance_ratio = var.cwiseQuotient(predicted).mean();
  s.position_sd_mm = 1000 * std::sqrt(position_var);
  s.predicted_position_sd_mm = 1000 * std::sqrt(predicted_position_var);
  return s;
}

// 150 draws on each of two views (a tilted tag at 1.2 m with noise of 3 gray levels; at 2 m
// through a distorting lens with 5). The covariances are first order and estimated from each
// picture (the edge samples' scatter, the data cells' transitions), so they are checked in two
// ways: (1) in expectation, the empirical variance of the corners and of the pose's position
// against the mean predicted one: ratios within [0.8, 1.25] (the sample variance of 150 draws
// has a relative sd of 0.12 per coordinate; a covariance off by 1.2x in sigma, 1.44 in variance,
// fails), and the coverage of the mean predicted pose covariance's 95 % ellipsoid >= 0.88 (4
// binomial sd below 0.95); (2) each draw's own covariance: coverage printed, and >= 0.7 (an
// estimated covariance covers less than its nominal 95 %, and perspective and lens distortion
// make the errors not quite Gaussian; docs/ros2.md states the figures).
TEST(MeasurementCovariance, EdgeFitCovariancesCoverTheSpreadOverSensorNoise) {
  struct Case {
    const char* name;
    bool distortion;
    obs::SE3 g;
    double noise;
  };
  for (const Case& c :
       {Case{"1.2 m, tilted, noise 3", false, facing_pose(1.2, 0.1, -0.05, {0.3, -0.2, 0.4}), 3.0},
        Case{"2 m, distortion, noise 5", true, facing_pose(2.0, -0.3, 0.2, {-0.4, 0.3, 1.1}),
             5.0}}) {
    const Spread s = spread_over_noise(testing::test_calibration(c.distortion), c.g, c.noise, 150);
    std::printf(
        "%s: corner variance empirical/predicted %.2f, position sd %.2f mm (predicted %.2f mm); "
        "95 %% coverage of the mean covariance: corners %.3f, pose %.3f; of each draw's own: "
        "corners %.3f, pose %.3f\n",
        c.name, s.corner_variance_ratio, s.position_sd_mm, s.predicted_position_sd_mm,
        s.corner_coverage_mean, s.pose_coverage_mean, s.corner_coverage, s.pose_coverage);
    EXPECT_GE(s.corner_variance_ratio, 0.8) << c.name;
    EXPECT_LE(s.corner_variance_ratio, 1.25) << c.name;
    const double position_ratio = s.position_sd_mm * s.position_sd_mm /
                                  (s.predicted_position_sd_mm * s.predicted_position_sd_mm);
    EXPECT_GE(position_ratio, 0.8) << c.name;
    EXPECT_LE(position_ratio, 1.25) << c.name;
    EXPECT_GE(s.pose_coverage_mean, 0.88) << c.name;
    EXPECT_GE(s.pose_coverage, 0.7) << c.name;
  }
}

}  // namespace
}  // namespace netvmo
