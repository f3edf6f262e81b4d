#include "netvmo/pipeline/frontend/refine.hpp"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "sampling.hpp"
#include "tag_square.hpp"

namespace netvmo::frontend {

namespace {

using detail::edge_offset;
using detail::min_side;

// One edge's total-least-squares line: through `mean` along unit `dir`, with the first-order
// variances of its two parameters from the scatter of its samples about it (s^2 = sum r^2 /
// (N - 2), r the samples' normal residuals): the offset along the normal at the mean, s^2 / N,
// and the angle, s^2 / sum t^2 (t the samples' positions along the line from the mean; the two
// are uncorrelated because sum t = 0).
struct EdgeLine {
  cv::Point2d mean, dir;
  double var_offset = 0.0, var_angle = 0.0;
};

// Corner k's first-order covariance from the lines of its two edges a (before it) and b (after
// it): the corner c satisfies n_a . (c - m_a) = 0 and n_b . (c - m_b) = 0, a line moved by
// (de, dphi) moves its points at position t along it by de + t dphi along its normal, so
// dc = M^-1 [de_a + t_a dphi_a; de_b + t_b dphi_b] with M = [n_a^T; n_b^T], t_x = d_x . (c - m_x).
// Fills the corner's rows of J (8 x 8: corners x the lines' (offset, angle) pairs).
void corner_jacobian(const std::array<EdgeLine, 4>& lines, const std::array<cv::Point2d, 4>& c,
                     Eigen::Matrix<double, 8, 8>& J) {
  J.setZero();
  for (int k = 0; k < 4; ++k) {
    const int la = (k + 3) % 4, lb = k;
    const EdgeLine& a = lines[static_cast<size_t>(la)];
    const EdgeLine& b = lines[static_cast<size_t>(lb)];
    const cv::Point2d& ck = c[static_cast<size_t>(k)];
    Eigen::Matrix2d M;
    M << -a.dir.y, a.dir.x, -b.dir.y, b.dir.x;  // the normals (any sign: the offsets' too)
    const Eigen::Matrix2d Mi = M.inverse();
    const double ta = a.dir.dot(ck - a.mean), tb = b.dir.dot(ck - b.mean);
    J.block<2, 1>(2 * k, 2 * la) = Mi.col(0);
    J.block<2, 1>(2 * k, 2 * la + 1) = Mi.col(0) * ta;
    J.block<2, 1>(2 * k, 2 * lb) = Mi.col(1);
    J.block<2, 1>(2 * k, 2 * lb + 1) = Mi.col(1) * tb;
  }
}

// The black border's width across each side as imaged [px]: the distance along the side's
// image normal from the side to the border's inner edge, one cell in, by the homography of the
// corners (the object square [0, n]^2, corner 0 at (0, n), 1 at (n, n), 2 at (n, 0), 3 at (0,
// 0)), the least of a tenth, half and nine tenths along the side. Seen far off the tag's normal
// a side is long while the border across it is thin: on datasets/floor_tag_grazing.yaml, 72-80
// degrees off the normal, 0.7-2.2 px across the thinnest side while the shortest side's cell
// (its length over n) is up to 4.7 px.
std::array<double, 4> border_widths(const std::array<cv::Point2d, 4>& c, int n) {
  std::array<double, 4> out;
  out.fill(std::numeric_limits<double>::infinity());
  const detail::SquareToImage map(c, n, nullptr);
  if (!map.ok()) return out;
  const detail::SquareSides sides(n);
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    const cv::Point2d a = c[ks], b = c[(ks + 1) % 4];
    const cv::Point2d d = (b - a) / cv::norm(b - a), normal(d.y, -d.x);
    for (double u : {0.1, 0.5, 0.9}) {
      const cv::Point2d on = sides.start[k] + u * n * sides.along[k];
      const std::vector<cv::Point2d> img = map.map({on, on - sides.outward[k]});
      out[ks] = std::min(out[ks], std::abs(normal.dot(img[1] - img[0])));
    }
  }
  return out;
}

bool refine_edge_lines(const cv::Mat& g, std::array<cv::Point2d, 4>& c, int border_cells,
                       const io::Calibration* calib, CornerCovariance* cov) {
  const double cell = min_side(c) / border_cells;
  if (cell < 1.5) return false;  // too small to sample the border reliably
  const double w = std::clamp(std::min(0.45 * cell, cell - 1.2), 1.0, 4.0);
  // Each side's window also stays within the border as imaged across it (not only within a
  // cell of the shortest side): a window that reaches the border's inner edge pulls the fitted
  // edge inward.
  const std::array<double, 4> widths = border_widths(c, border_cells);
  cv::Point2d centroid(0, 0);
  for (const auto& p : c) centroid += 0.25 * p;
  const bool undistort = calib && calib->has_distortion();
  std::array<EdgeLine, 4> lines;  // in ideal (undistorted) pixels if undistort
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d a = c[k], b = c[(k + 1) % 4];
    const double len = cv::norm(b - a);
    const cv::Point2d d = (b - a) / len;
    cv::Point2d n(d.y, -d.x);
    if (n.dot(0.5 * (a + b) - centroid) < 0) n = -n;  // outward: black inside, white outside
    const double skip = w + 1.5;
    const double across = widths[static_cast<size_t>(k)];
    const double wk =
        std::min(w, std::clamp(std::min(0.45 * across, across - 1.2), 1.0, 4.0));  // NaN: w
    std::vector<cv::Point2d> pts;
    for (double t = skip; t <= len - skip; t += 1.0) {
      const cv::Point2d p = a + t * d;
      double s = 0.0;
      if (edge_offset(g, p, n, wk, s, true)) pts.push_back(p + s * n);
    }
    if (pts.size() < 4) return false;
    if (undistort) pts = io::ideal_pixels(pts, *calib);
    // Total least squares line through the points.
    cv::Point2d mean(0, 0);
    for (const auto& p : pts) mean += p;
    mean *= 1.0 / static_cast<double>(pts.size());
    double sxx = 0, sxy = 0, syy = 0;
    for (const auto& p : pts) {
      const cv::Point2d q = p - mean;
      sxx += q.x * q.x;
      sxy += q.x * q.y;
      syy += q.y * q.y;
    }
    const double theta = 0.5 * std::atan2(2 * sxy, sxx - syy);  // principal direction
    EdgeLine& line = lines[static_cast<size_t>(k)];
    line.mean = mean;
    line.dir = cv::Point2d(std::cos(theta), std::sin(theta));
    const cv::Point2d normal(-line.dir.y, line.dir.x);
    double rr = 0.0, tt = 0.0;
    std::vector<double> r(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
      r[i] = normal.dot(pts[i] - mean);
      const double t = line.dir.dot(pts[i] - mean);
      rr += r[i] * r[i];
      tt += t * t;
    }
    const double s2 = rr / static_cast<double>(pts.size() - 2);
    // Neighbouring samples share pixels (their windows across the edge and the bilinear
    // interpolation overlap), so their residuals are correlated: the variances of a mean over N
    // samples grow by tau = 1 + 2 sum_k rho_k (rho_k the residuals' autocorrelation at lag k,
    // summed over the lags a window can reach, 2 w + 2 samples; negative sums count as 0).
    double tau = 1.0;
    if (rr > 0.0) {
      const int lags = static_cast<int>(std::ceil(2.0 * wk)) + 2;
      double sum_rho = 0.0;
      for (int k = 1; k <= lags && static_cast<size_t>(k) < r.size(); ++k) {
        double c = 0.0;
        for (size_t i = 0; i + static_cast<size_t>(k) < r.size(); ++i)
          c += r[i] * r[i + static_cast<size_t>(k)];
        sum_rho += c / rr;
      }
      tau = std::max(1.0, 1.0 + 2.0 * sum_rho);
    }
    line.var_offset = tau * s2 / static_cast<double>(pts.size());
    line.var_angle = tt > 0.0 ? tau * s2 / tt : 0.0;
  }
  std::array<cv::Point2d, 4> out;
  for (int k = 0; k < 4; ++k) {
    // corner k = intersection of edge k-1 (c[k-1] -> c[k]) and edge k (c[k] -> c[k+1])
    const EdgeLine& l1 = lines[static_cast<size_t>((k + 3) % 4)];
    const EdgeLine& l2 = lines[static_cast<size_t>(k)];
    const auto corner = detail::intersect_lines(l1.mean, l1.dir, l2.mean, l2.dir);
    if (!corner) return false;
    out[static_cast<size_t>(k)] = *corner;
  }
  std::optional<CornerCovariance> fit_cov;
  if (cov) {
    Eigen::Matrix<double, 8, 8> J;
    corner_jacobian(lines, out, J);
    Eigen::Matrix<double, 8, 1> var;
    for (int k = 0; k < 4; ++k) {
      var(2 * k) = lines[static_cast<size_t>(k)].var_offset;
      var(2 * k + 1) = lines[static_cast<size_t>(k)].var_angle;
    }
    fit_cov = J * var.asDiagonal() * J.transpose();
  }
  if (undistort) {
    const auto px = io::distorted_pixels({out.begin(), out.end()}, *calib);
    std::copy(px.begin(), px.end(), out.begin());
  }
  const double max_move = std::max(1.5, 0.5 * cell);
  for (int k = 0; k < 4; ++k)
    if (!(cv::norm(out[static_cast<size_t>(k)] - c[static_cast<size_t>(k)]) <= max_move))
      return false;  // implausible: keep libapriltag's corners
  c = out;
  if (cov) *cov = *fit_cov;
  return true;
}

void refine_subpix(const cv::Mat& g, std::array<cv::Point2d, 4>& c, int border_cells) {
  const double cell = min_side(c) / border_cells;
  const int win = std::clamp(static_cast<int>(std::lround(0.5 * cell)), 2, 6);
  std::vector<cv::Point2f> pts;
  for (const auto& p : c) pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  for (const auto& p : pts)  // cornerSubPix needs the window inside the image
    if (p.x < win + 1 || p.y < win + 1 || p.x > g.cols - win - 2 || p.y > g.rows - win - 2) return;
  cv::cornerSubPix(g, pts, cv::Size(win, win), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 0.001));
  const double max_move = std::max(1.5, 0.5 * cell);
  std::array<cv::Point2d, 4> out;
  for (size_t k = 0; k < 4; ++k) {
    out[k] = cv::Point2d(pts[k].x, pts[k].y);
    if (!(cv::norm(out[k] - c[k]) <= max_move)) return;
  }
  c = out;
}

}  // namespace

const char* to_string(Refinement r) {
  switch (r) {
    case Refinement::none:
      return "none";
    case Refinement::corner_subpix:
      return "subpix";
    case Refinement::edge_lines:
      return "edges";
  }
  return "?";
}

Refinement parse_refinement(const std::string& name) {
  if (name == "none") return Refinement::none;
  if (name == "subpix") return Refinement::corner_subpix;
  if (name == "edges") return Refinement::edge_lines;
  throw InputError("unknown refinement '" + name + "' (expected none, subpix or edges)");
}

std::optional<CornerCovariance> refine_corners(const cv::Mat& gray,
                                               std::array<cv::Point2d, 4>& corners, Refinement mode,
                                               int border_cells, const io::Calibration* calib) {
  CV_Assert(gray.type() == CV_8UC1);
  switch (mode) {
    case Refinement::none:
      return std::nullopt;
    case Refinement::corner_subpix:
      refine_subpix(gray, corners, border_cells);
      return std::nullopt;
    case Refinement::edge_lines: {
      CornerCovariance cov;
      if (refine_edge_lines(gray, corners, border_cells, calib, &cov)) return cov;
      return std::nullopt;
    }
  }
  return std::nullopt;
}

}  // namespace netvmo::frontend
