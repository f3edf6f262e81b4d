#include "netvmo/pipeline/frontend/pnp.hpp"

#include <visp3/core/vpException.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpPoint.h>
#include <visp3/vision/vpPose.h>
#include <Eigen/Dense>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <stdexcept>

namespace netvmo::frontend {

namespace {

obs::SE3 to_se3(const vpHomogeneousMatrix& M) {
  obs::SE3 g = obs::SE3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      g.linear()(r, c) = M[static_cast<unsigned>(r)][static_cast<unsigned>(c)];
    g.translation()[r] = M[static_cast<unsigned>(r)][3];
  }
  return g;
}

bool in_front(const obs::SE3& g, const obs::FeatureModel& model) {
  for (const auto& p : model.points_o)
    if (!((g * p).z() > 0.0)) return false;
  return true;
}

}  // namespace

std::optional<PnpResult> pnp_pose(const Eigen::VectorXd& f, const obs::FeatureModel& model) {
  const size_t m = model.points_o.size();
  if (m < 4 || f.size() != static_cast<Eigen::Index>(2 * m))
    throw std::invalid_argument("pnp_pose: need m >= 4 points and f of size 2m");
  if (model.lambda != 1.0)
    throw std::invalid_argument("pnp_pose: expects normalized coordinates (lambda = 1)");
  if (!f.allFinite()) return std::nullopt;

  std::vector<vpPoint> pts;
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (size_t l = 0; l < m; ++l) {
    const auto& P = model.points_o[l];
    vpPoint p;
    p.setWorldCoordinates(P.x(), P.y(), P.z());
    const double x = f[static_cast<Eigen::Index>(2 * l)],
                 y = f[static_cast<Eigen::Index>(2 * l + 1)];
    p.set_x(x);
    p.set_y(y);
    pts.push_back(p);
    obj.emplace_back(P.x(), P.y(), P.z());
    img.emplace_back(x, y);
  }

  std::optional<PnpResult> best;
  auto consider = [&](vpPose::vpPoseMethodType method, vpHomogeneousMatrix cMo) {
    try {
      vpPose pose;
      pose.addPoints(pts);
      pose.setVvsIterMax(200);
      if (!pose.computePose(method, cMo)) return;
      if (method != vpPose::VIRTUAL_VS) pose.computePose(vpPose::VIRTUAL_VS, cMo);
      const obs::SE3 g = to_se3(cMo);
      if (!g.matrix().allFinite() || !in_front(g, model)) return;
      const double rms = std::sqrt(pose.computeResidual(cMo) / static_cast<double>(m));
      if (!best || rms < best->residual) best = PnpResult{g, rms};
    } catch (const vpException&) {
      // this candidate failed (degenerate configuration); others may succeed
    }
  };
  consider(vpPose::LAGRANGE_VIRTUAL_VS, vpHomogeneousMatrix());
  consider(vpPose::DEMENTHON_VIRTUAL_VS, vpHomogeneousMatrix());
  // OpenCV's IPPE gives both solutions of the planar ambiguity as starting points.
  bool planar = true;
  for (const auto& p : model.points_o) planar = planar && p.z() == 0.0;
  if (planar) {
    try {
      std::vector<cv::Mat> rvecs, tvecs;
      cv::solvePnPGeneric(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvecs, tvecs, false,
                          cv::SOLVEPNP_IPPE);
      for (size_t k = 0; k < rvecs.size(); ++k) {
        const cv::Vec3d r(rvecs[k]), t(tvecs[k]);
        consider(vpPose::VIRTUAL_VS, vpHomogeneousMatrix(t[0], t[1], t[2], r[0], r[1], r[2]));
      }
    } catch (const cv::Exception&) {
    }
  }
  return best;
}

Eigen::MatrixXd pnp_jacobian(const obs::SE3& g_io, const std::vector<obs::Vec3>& points_o) {
  const auto m = static_cast<Eigen::Index>(points_o.size());
  Eigen::MatrixXd A(2 * m, 6);
  for (Eigen::Index l = 0; l < m; ++l) {
    const obs::Vec3 Rp = g_io.linear() * points_o[static_cast<size_t>(l)];
    const obs::Vec3 X = Rp + g_io.translation();
    if (!(X.z() > 0.0)) throw std::domain_error("pnp_covariance: a point is not in front");
    Eigen::Matrix<double, 2, 3> P;
    P << 1.0 / X.z(), 0.0, -X.x() / (X.z() * X.z()), 0.0, 1.0 / X.z(), -X.y() / (X.z() * X.z());
    A.block<2, 3>(2 * l, 0) = P;
    A.block<2, 3>(2 * l, 3) = -P * obs::hat(Rp);
  }
  return A;
}

PoseCovariance pnp_covariance(const obs::SE3& g_io, const std::vector<obs::Vec3>& points_o,
                              const Eigen::MatrixXd& f_cov) {
  const auto n = static_cast<Eigen::Index>(2 * points_o.size());
  if (points_o.size() < 4 || f_cov.rows() != n || f_cov.cols() != n)
    throw std::invalid_argument("pnp_covariance: need m >= 4 points and a 2m x 2m f_cov");
  const Eigen::MatrixXd A = pnp_jacobian(g_io, points_o);
  const Eigen::Matrix<double, 6, 6> AtA_inv = (A.transpose() * A).inverse();
  const Eigen::MatrixXd B = AtA_inv * A.transpose();  // A^+
  PoseCovariance C = B * f_cov * B.transpose();
  return 0.5 * (C + C.transpose());
}

}  // namespace netvmo::frontend
