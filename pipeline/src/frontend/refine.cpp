#include "netvmo/pipeline/frontend/refine.hpp"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "sampling.hpp"
#include "tag_square.hpp"

namespace netvmo::frontend {

namespace {

using detail::edge_offset;
using detail::edge_spread;

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

// The sub-pixel samples of a quad's four outer edges that the edge-line fit uses: along each
// side, one a pixel, its ends skipped, each found across the side within a window that stays
// inside the border as imaged across it (a window that reaches the border's inner edge pulls
// the fitted edge inward). Pixels, distorted as the image is.
class SideSampler {
 public:
  SideSampler(const cv::Mat& g, const std::array<cv::Point2d, 4>& c, int border_cells)
      : g_(g), c_(c), cell_(narrowest_side(c) / border_cells) {
    w_ = std::clamp(std::min(0.45 * cell_, cell_ - 1.2), 1.0, 4.0);
    widths_ = border_widths(c, border_cells);
    for (const auto& p : c) centroid_ += 0.25 * p;
  }
  /// Whether the cells are large enough to sample the border reliably.
  bool ok() const { return cell_ >= 1.5; }
  double cell() const { return cell_; }
  /// Side k's unit normal pointing out of the quad (black inside, white outside).
  cv::Point2d outward(int k) const {
    const cv::Point2d a = c_[static_cast<size_t>(k)], b = c_[static_cast<size_t>((k + 1) % 4)];
    const cv::Point2d d = (b - a) / cv::norm(b - a);
    const cv::Point2d n(d.y, -d.x);
    return n.dot(0.5 * (a + b) - centroid_) < 0 ? -n : n;
  }
  /// Side k's samples, one every `step` px along it.
  std::vector<cv::Point2d> samples(int k, double step = 1.0) const {
    const cv::Point2d a = c_[static_cast<size_t>(k)], b = c_[static_cast<size_t>((k + 1) % 4)];
    const double len = cv::norm(b - a);
    const cv::Point2d d = (b - a) / len;
    const cv::Point2d n = outward(k);
    const double skip = w_ + 1.5;
    const double wk = window(k);
    std::vector<cv::Point2d> pts;
    for (double t = skip; t <= len - skip; t += step) {
      const cv::Point2d p = a + t * d;
      double s = 0.0;
      if (edge_offset(g_, p, n, wk, s, true)) pts.push_back(p + s * n);
    }
    return pts;
  }
  /// The black border's width across side k as imaged [px] (border_widths()).
  double across(int k) const { return widths_[static_cast<size_t>(k)]; }
  /// The half-width of the window across side k's edge [px].
  double window(int k) const {
    const double across = widths_[static_cast<size_t>(k)];
    return std::min(w_, std::clamp(std::min(0.45 * across, across - 1.2), 1.0, 4.0));  // NaN: w
  }

 private:
  const cv::Mat& g_;
  std::array<cv::Point2d, 4> c_;
  double cell_, w_;
  std::array<double, 4> widths_;
  cv::Point2d centroid_{0, 0};
};

// Neighbouring samples share pixels (their windows across the edge and the bilinear
// interpolation overlap), so their residuals `r` (sum of squares `rr`) are correlated: the
// variances of a mean over N samples grow by tau = 1 + 2 sum_k rho_k (rho_k the residuals'
// autocorrelation at lag k, summed over the lags a window of half-width `wk` can reach, 2 wk + 2
// samples; negative sums count as 0).
double correlation_inflation(const std::vector<double>& r, double rr, double wk) {
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
  return tau;
}

// The total-least-squares line through one edge's samples (at least 3), and its variances
// (EdgeLine); `wk` the half-width of the window across the edge they were found in.
EdgeLine fit_edge_line(const std::vector<cv::Point2d>& pts, double wk) {
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
  EdgeLine line;
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
  const double tau = correlation_inflation(r, rr, wk);
  line.var_offset = tau * s2 / static_cast<double>(pts.size());
  line.var_angle = tt > 0.0 ? tau * s2 / tt : 0.0;
  return line;
}

bool refine_edge_lines(const cv::Mat& g, std::array<cv::Point2d, 4>& c, int border_cells,
                       const io::Calibration* calib, CornerCovariance* cov, EdgeSamples* samples) {
  if (samples) *samples = EdgeSamples{};
  const auto fail = [samples] {  // no lines fitted: no samples either
    if (samples) *samples = EdgeSamples{};
    return false;
  };
  const SideSampler sampler(g, c, border_cells);
  if (!sampler.ok()) return false;  // too small to sample the border reliably
  const double cell = sampler.cell();
  const bool undistort = calib && calib->has_distortion();
  std::array<EdgeLine, 4> lines;  // in ideal (undistorted) pixels if undistort
  for (int k = 0; k < 4; ++k) {
    std::vector<cv::Point2d> pts = sampler.samples(k);
    const double wk = sampler.window(k);
    if (pts.size() < 4) return fail();
    if (samples) samples->sides[static_cast<size_t>(k)] = pts;
    if (undistort) pts = io::ideal_pixels(pts, *calib);
    if (samples && undistort) samples->ideal[static_cast<size_t>(k)] = pts;
    lines[static_cast<size_t>(k)] = fit_edge_line(pts, wk);
  }
  std::array<cv::Point2d, 4> out;
  for (int k = 0; k < 4; ++k) {
    // corner k = intersection of edge k-1 (c[k-1] -> c[k]) and edge k (c[k] -> c[k+1])
    const EdgeLine& l1 = lines[static_cast<size_t>((k + 3) % 4)];
    const EdgeLine& l2 = lines[static_cast<size_t>(k)];
    const auto corner = detail::intersect_lines(l1.mean, l1.dir, l2.mean, l2.dir);
    if (!corner) return fail();
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
      return fail();  // implausible: keep libapriltag's corners
  c = out;
  if (cov) *cov = *fit_cov;
  return true;
}

void refine_subpix(const cv::Mat& g, std::array<cv::Point2d, 4>& c, int border_cells) {
  const double cell = narrowest_side(c) / border_cells;
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
                                               int border_cells, const io::Calibration* calib,
                                               EdgeSamples* samples) {
  CV_Assert(gray.type() == CV_8UC1);
  if (samples) *samples = EdgeSamples{};
  switch (mode) {
    case Refinement::none:
      return std::nullopt;
    case Refinement::corner_subpix:
      refine_subpix(gray, corners, border_cells);
      return std::nullopt;
    case Refinement::edge_lines: {
      CornerCovariance cov;
      if (refine_edge_lines(gray, corners, border_cells, calib, &cov, samples)) return cov;
      return std::nullopt;
    }
  }
  return std::nullopt;
}

cv::Point2d side_bow_at(const SideBow& side, const cv::Point2d& p) {
  if (!(side.half > 0.0)) return {0.0, 0.0};
  const double u = side.dir.dot(p - side.origin) / side.half;
  return (side.coef[0] + u * (side.coef[1] + u * side.coef[2])) * side.normal;
}

QuadBow quad_bow(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int border_cells,
                 const io::Calibration* calib, const EdgeSamples* given) {
  CV_Assert(gray.type() == CV_8UC1);
  QuadBow out;
  const SideSampler sampler(gray, corners, border_cells);
  if (!sampler.ok()) return out;
  const bool undistort = calib && calib->has_distortion();
  // Each side's samples (the edge-line fit's, else about 40 of them: one a pixel up to a side of
  // 40 px; in ideal pixels too where the calibration has distortion) and its edge's blur: the
  // median spread of the intensity differences across it at a dozen of them (edge_spread,
  // window the border's width as imaged), less that of a sharp edge integrated over the pixel
  // and interpolated (0.25 px^2).
  std::array<std::vector<cv::Point2d>, 4> samples, ideal;
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    const double len = cv::norm(corners[(ks + 1) % 4] - corners[ks]);
    if (given && !given->sides[ks].empty()) {
      samples[ks] = given->sides[ks];
      if (undistort && given->ideal[ks].size() == samples[ks].size()) ideal[ks] = given->ideal[ks];
    } else {
      samples[ks] = sampler.samples(k, std::max(1.0, std::floor(len / 40.0)));
    }
    if (undistort && ideal[ks].empty()) ideal[ks] = io::ideal_pixels(samples[ks], *calib);
    std::vector<double> spreads;
    const size_t stride = std::max<size_t>(1, samples[ks].size() / 12);
    for (size_t i = 0; i < samples[ks].size(); i += stride) {
      const double sp =
          edge_spread(gray, samples[ks][i], sampler.outward(k), 0.5 * sampler.across(k));
      if (!std::isnan(sp)) spreads.push_back(sp);
    }
    if (spreads.empty()) return out;
    std::nth_element(spreads.begin(), spreads.begin() + static_cast<long>(spreads.size() / 2),
                     spreads.end());
    const double sp = spreads[spreads.size() / 2];
    out.sides[ks].blur = std::sqrt(std::max(0.0, sp * sp - 0.25));
  }
  std::array<cv::Point2d, 4> c = corners;
  if (undistort) {
    const auto ideal = io::ideal_pixels({c.begin(), c.end()}, *calib);
    std::copy(ideal.begin(), ideal.end(), c.begin());
  }
  std::array<cv::Point2d, 4> normal;  // each side's line normal, the sign of its offsets
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k), next = static_cast<size_t>((k + 1) % 4),
                 prev = static_cast<size_t>((k + 3) % 4);
    // The border's inner edge, blurred, must stay out of the window across the outer edge: else
    // the data cells next to the border (white at some, black at others) move the samples.
    if (!(sampler.across(k) - sampler.window(k) >= 3.0 * out.sides[ks].blur + 0.5)) return out;
    // Near a corner the other side's blurred edge lightens the black inside and pulls the
    // samples inward: left out within 3 blur + 1 px of the other side (along this side: that
    // over the sine of the corner's angle), at most a quarter of the side.
    const cv::Point2d a = corners[ks], b = corners[next];
    const double len = cv::norm(b - a);
    // the skip at corner `at`, where this side meets `other` (that side's far corner `beyond`)
    const auto skip = [&](size_t at, size_t beyond, size_t other) {
      const cv::Point2d u = (at == ks ? b - a : a - b), v = corners[beyond] - corners[at];
      const double sine = std::abs(u.cross(v)) / (cv::norm(u) * cv::norm(v));
      return std::min(0.25 * len, (3.0 * out.sides[other].blur + 1.0) / std::max(sine, 0.25));
    };
    const double from = skip(ks, prev, prev);
    const double to = len - skip(next, static_cast<size_t>((k + 2) % 4), next);
    std::vector<cv::Point2d> pts;  // ideal pixels where the calibration has distortion
    for (size_t i = 0; i < samples[ks].size(); ++i) {
      const double t = (samples[ks][i] - a).dot(b - a) / len;
      if (t >= from && t <= to) pts.push_back(undistort ? ideal[ks][i] : samples[ks][i]);
    }
    if (pts.size() < 8) return out;
    const double wk = sampler.window(k);
    const EdgeLine line = fit_edge_line(pts, wk);
    const cv::Point2d n(-line.dir.y, line.dir.x);
    normal[static_cast<size_t>(k)] = n;
    // offset r = a0 + a1 u + a2 u^2 across the line, u = t / h (t along it from the samples'
    // mean, h half the side's length: the fit's columns of one scale)
    const double h =
        0.5 * cv::norm(c[static_cast<size_t>((k + 1) % 4)] - c[static_cast<size_t>(k)]);
    const size_t m = pts.size();
    std::vector<double> us(m), r(m);
    Eigen::Matrix3d XtX = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Xty = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < m; ++i) {
      const cv::Point2d q = pts[i] - line.mean;
      us[i] = line.dir.dot(q) / h;
      r[i] = n.dot(q);
      const Eigen::Vector3d x(1.0, us[i], us[i] * us[i]);
      XtX += x * x.transpose();
      Xty += r[i] * x;
    }
    const Eigen::Vector3d beta = XtX.ldlt().solve(Xty);
    double rr = 0.0;
    for (size_t i = 0; i < m; ++i) {
      r[i] -= beta(0) + us[i] * (beta(1) + us[i] * beta(2));  // the quadratic's residual
      rr += r[i] * r[i];
    }
    const double s2 = rr / static_cast<double>(m - 3);
    const Eigen::Matrix3d cov = correlation_inflation(r, rr, wk) * s2 * XtX.inverse();
    SideBow& side = out.sides[static_cast<size_t>(k)];
    side.samples = static_cast<int>(m);
    side.origin = line.mean;
    side.dir = line.dir;
    side.normal = n;
    side.half = h;
    side.coef = {beta(0), beta(1), beta(2)};
    for (int e = 0; e < 2; ++e) {
      const cv::Point2d end = c[static_cast<size_t>((k + e) % 4)];
      const double u = line.dir.dot(end - line.mean) / h;
      const Eigen::Vector3d x(1.0, u, u * u);
      side.end_offset[static_cast<size_t>(e)] = x.dot(beta);  // the line's own offset is 0
      side.end_se[static_cast<size_t>(e)] = std::sqrt(x.dot(cov * x));
    }
  }
  // Corner k lies where side k-1 (its second end) and side k (its first end) end: moved from the
  // lines' intersection by v with n_a . v = r_a, n_b . v = r_b.
  for (int k = 0; k < 4; ++k) {
    const size_t a = static_cast<size_t>((k + 3) % 4), b = static_cast<size_t>(k);
    Eigen::Matrix2d M;
    M << normal[a].x, normal[a].y, normal[b].x, normal[b].y;
    if (!(std::abs(M.determinant()) > 1e-6)) return out;
    const Eigen::Matrix2d Mi = M.inverse();
    const Eigen::Vector2d r(out.sides[a].end_offset[1], out.sides[b].end_offset[0]);
    const Eigen::Vector2d v = Mi * r;
    const Eigen::Matrix2d C =
        Mi *
        Eigen::Vector2d(std::pow(out.sides[a].end_se[1], 2), std::pow(out.sides[b].end_se[0], 2))
            .asDiagonal() *
        Mi.transpose();
    out.corner_shift[static_cast<size_t>(k)] = cv::Point2d(v.x(), v.y());
    const double len = v.norm();
    out.corner_se[static_cast<size_t>(k)] =
        len > 0.0 ? std::sqrt((v / len).dot(C * (v / len))) : std::sqrt(0.5 * C.trace());
  }
  out.measured = true;
  return out;
}

}  // namespace netvmo::frontend
