#include "netvmo/observer/jacobian.hpp"

#include <Eigen/Cholesky>
#include <stdexcept>
#include <string>

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

namespace {
using Block = Eigen::Matrix<double, 2, 6>;

/// Row block l of the image Jacobian (see image_jacobian) for the target point po and, in f_bar,
/// its image lambda / z [x; y] under g_bar (eq:visual_mea).
Block jacobian_block(const SE3& g_bar, const Vec3& po, double lambda, Eigen::Vector2d& f_bar) {
  const Vec3 p = g_bar * po;
  if (!(p.z() > 0.0)) throw std::domain_error("feature point behind the camera (z <= 0)");
  f_bar = lambda / p.z() * p.head<2>();
  Eigen::Matrix<double, 2, 3> dpi;  // d(lambda [x;y]/z) / d[x;y;z]
  dpi << 1.0, 0.0, -p.x() / p.z(), 0.0, 1.0, -p.y() / p.z();
  dpi *= lambda / p.z();
  const Eigen::Matrix<double, 2, 3> A = dpi * g_bar.linear();
  Block J;
  J.leftCols<3>() = A;              // d/dp_e
  J.rightCols<3>() = -A * hat(po);  // d/de_R: R (e_R x p_ol) = -R hat(p_ol) e_R
  return J;
}
}  // namespace

Eigen::MatrixXd image_jacobian(const SE3& g_bar, const FeatureModel& model) {
  const auto m = static_cast<Eigen::Index>(model.points_o.size());
  Eigen::MatrixXd J(2 * m, 6);
  Eigen::Vector2d f_bar;
  for (Eigen::Index l = 0; l < m; ++l)
    J.block<2, 6>(2 * l, 0) =
        jacobian_block(g_bar, model.points_o[static_cast<size_t>(l)], model.lambda, f_bar);
  return J;
}

Vec6 reconstruct_error(const SE3& g_bar, const Eigen::VectorXd& f, const FeatureModel& model) {
  const auto m = static_cast<Eigen::Index>(model.points_o.size());
  if (f.size() != 2 * m)
    throw std::domain_error("feature vector of " + std::to_string(f.size()) +
                            " values for a target of " + std::to_string(m) + " feature points");
  // J^dagger (f - f_bar) = (J^T J)^-1 J^T (f - f_bar) with J^T J and J^T (f - f_bar) summed over
  // the points' row blocks (fixed-size, no allocation). J has full column rank for m >= 4
  // non-degenerate points.
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  Vec6 Jtf = Vec6::Zero();
  Eigen::Vector2d f_bar;
  for (Eigen::Index l = 0; l < m; ++l) {
    const Block J =
        jacobian_block(g_bar, model.points_o[static_cast<size_t>(l)], model.lambda, f_bar);
    JtJ.noalias() += J.transpose() * J;
    Jtf.noalias() += J.transpose() * (f.segment<2>(2 * l) - f_bar);
  }
  return JtJ.ldlt().solve(Jtf);  // (eq:eei)
}

}  // namespace netvmo::obs
