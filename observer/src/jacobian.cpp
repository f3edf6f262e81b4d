#include "netvmo/observer/jacobian.hpp"

#include <Eigen/Cholesky>
#include <stdexcept>

namespace netvmo::obs {

FeatureModel FeatureModel::square(double side, double lambda) {
  const double h = 0.5 * side;
  FeatureModel m;
  m.points_o = {Vec3(-h, -h, 0.0), Vec3(h, -h, 0.0), Vec3(h, h, 0.0), Vec3(-h, h, 0.0)};
  m.lambda = lambda;
  return m;
}

Eigen::VectorXd project(const SE3& g_io, const FeatureModel& model) {
  const auto m = static_cast<Eigen::Index>(model.points_o.size());
  Eigen::VectorXd f(2 * m);
  for (Eigen::Index l = 0; l < m; ++l) {
    const Vec3 p = g_io * model.points_o[static_cast<size_t>(l)];
    if (!(p.z() > 0.0)) throw std::domain_error("feature point behind the camera (z <= 0)");
    f.segment<2>(2 * l) = model.lambda / p.z() * p.head<2>();  // (eq:visual_mea)
  }
  return f;
}

Eigen::MatrixXd image_jacobian(const SE3& g_bar, const FeatureModel& model) {
  const auto m = static_cast<Eigen::Index>(model.points_o.size());
  Eigen::MatrixXd J(2 * m, 6);
  const Mat3 R = g_bar.linear();
  for (Eigen::Index l = 0; l < m; ++l) {
    const Vec3& po = model.points_o[static_cast<size_t>(l)];
    const Vec3 p = g_bar * po;
    if (!(p.z() > 0.0)) throw std::domain_error("feature point behind the camera (z <= 0)");
    Eigen::Matrix<double, 2, 3> dpi;  // d(lambda [x;y]/z) / d[x;y;z]
    dpi << 1.0, 0.0, -p.x() / p.z(), 0.0, 1.0, -p.y() / p.z();
    dpi *= model.lambda / p.z();
    const Eigen::Matrix<double, 2, 3> A = dpi * R;
    J.block<2, 3>(2 * l, 0) = A;             // d/dp_e
    J.block<2, 3>(2 * l, 3) = -A * hat(po);  // d/de_R: R (e_R x p_ol) = -R hat(p_ol) e_R
  }
  return J;
}

Vec6 reconstruct_error(const SE3& g_bar, const Eigen::VectorXd& f, const FeatureModel& model) {
  const Eigen::MatrixXd J = image_jacobian(g_bar, model);
  const Eigen::VectorXd fe = f - project(g_bar, model);
  // J has full column rank for m >= 4 non-degenerate points; J^dagger = (J^T J)^-1 J^T.
  const Eigen::Matrix<double, 6, 6> JtJ = J.transpose() * J;
  return JtJ.ldlt().solve(J.transpose() * fe);  // (eq:eei)
}

}  // namespace netvmo::obs
