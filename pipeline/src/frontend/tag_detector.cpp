#include "netvmo/pipeline/frontend/tag_detector.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::frontend {

namespace {

/// libapriltag reports pixel centres at +0.5 (measured, see tests/pipeline/test_detector.cpp).
constexpr double kApriltagPixelOffset = 0.5;

/// A target found on a normalised copy (SearchOptions::normalized) is rejected when its corners
/// refined on the image and on the copy differ by more than this [px] (a shadow boundary along
/// a border edge; measured on moving_target: 0.01-0.21 px where the corners are right, 0.53 px
/// where the image fit put a corner 1.4 px off).
constexpr double kMaxNormalizedDisagreement = 0.35;

void validate(const DetectorSettings& s) {
  auto bad = [](const std::string& what) { throw InputError("detector settings: " + what); };
  if (!render::find_tag_family(s.family))
    bad("unsupported tag family '" + s.family + "' (supported: " + render::tag_family_names() +
        ")");
  if (!(s.quad_decimate >= 1.0)) bad("quad_decimate must be >= 1");
  if (!(s.quad_sigma >= 0.0)) bad("quad_sigma must be >= 0");
  if (s.nthreads < 1) bad("nthreads must be >= 1");
  if (!(s.decode_sharpening >= 0.0)) bad("decode_sharpening must be >= 0");
  if (s.bits_corrected < 0 || s.bits_corrected > 3) bad("bits_corrected must be in 0..3");
  if (s.min_white_black_diff < 0 || s.min_white_black_diff > 255)
    bad("min_white_black_diff must be in 0..255");
  if (s.target_id < 0) bad("target id must be >= 0");
  for (size_t k = 0; k < s.bundle_ids.size(); ++k) {
    if (s.bundle_ids[k] < 0) bad("bundle ids must be >= 0");
    if (s.bundle_ids[k] == s.target_id ||
        std::count(s.bundle_ids.begin(), s.bundle_ids.begin() + static_cast<long>(k),
                   s.bundle_ids[k]))
      bad("tag id " + std::to_string(s.bundle_ids[k]) + " listed twice in the target");
  }
  if (!s.tags_per_target.empty()) {
    size_t total = 0;
    for (int c : s.tags_per_target) {
      if (c < 1) bad("tags_per_target: every target has at least one tag");
      total += static_cast<size_t>(c);
    }
    if (total != 1 + s.bundle_ids.size())
      bad("tags_per_target: the counts must add up to the number of tags (" +
          std::to_string(1 + s.bundle_ids.size()) + ")");
  }
  if (!(s.min_decision_margin >= 0.0)) bad("min_decision_margin must be >= 0");
  if (s.max_hamming < 0) bad("max_hamming must be >= 0");
  if (!(s.border_min_contrast >= 0.0 && s.border_min_contrast <= 1.0))
    bad("border_min_contrast must be in 0..1");
  if (!(s.border_max_failed_fraction >= 0.0 && s.border_max_failed_fraction <= 1.0))
    bad("border_max_failed_fraction must be in 0..1");
  if (!(s.border_max_thickness_error > 0.0)) bad("border_max_thickness_error must be > 0");
  if (!(s.border_blur_allowance >= 0.0 && s.border_blur_allowance <= 10.0))
    bad("border_blur_allowance must be in 0..10");
}

inline double sample_bilinear(const cv::Mat& g, double x, double y) {
  x = std::clamp(x, 0.0, g.cols - 1.000001);
  y = std::clamp(y, 0.0, g.rows - 1.000001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double ax = x - x0, ay = y - y0;
  const uchar* r0 = g.ptr<uchar>(y0);
  const uchar* r1 = g.ptr<uchar>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) +
         ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

double min_side(const std::array<cv::Point2d, 4>& c) {
  double m = 1e300;
  for (int k = 0; k < 4; ++k) m = std::min(m, cv::norm(c[(k + 1) % 4] - c[k]));
  return m;
}

/// Sub-pixel position of the dark-to-bright step along the outward normal n through p: the
/// centroid of the intensity differences in a window re-centred on the estimate (exact for a
/// pixel-integrated straight step edge sampled with bilinear interpolation). Returns false if the
/// step is too weak or the estimate leaves the window.
bool edge_offset(const cv::Mat& g, cv::Point2d p, cv::Point2d n, double w, double& s_out) {
  constexpr double h = 0.25;
  const int m = static_cast<int>(std::ceil(w / h));
  double s0 = 0.0;
  for (int iter = 0; iter < 3; ++iter) {
    double sum_g = 0.0, sum_sg = 0.0;
    double prev = sample_bilinear(g, p.x + (s0 - m * h) * n.x, p.y + (s0 - m * h) * n.y);
    for (int j = -m + 1; j <= m; ++j) {
      const double s = s0 + j * h;
      const double cur = sample_bilinear(g, p.x + s * n.x, p.y + s * n.y);
      const double d = cur - prev;
      sum_g += d;
      sum_sg += d * (s - 0.5 * h);
      prev = cur;
    }
    if (sum_g < 8.0) return false;  // less than 8 gray levels of contrast across the edge
    const double s = sum_sg / sum_g;
    if (std::abs(s) > w + 1.0) return false;
    s0 = s;
  }
  s_out = s0;
  return true;
}

/// Spread of a dark-to-bright edge along the unit normal n through p (p on the edge): the
/// standard deviation of the intensity differences within +-w, sampled every 0.25 px with
/// bilinear interpolation [px]. For a step blurred by a Gaussian of sigma s, integrated over the
/// pixel (variance 1/12 px^2) and interpolated bilinearly (variance 1/6 px^2), it is
/// sqrt(s^2 + 0.25) until the window truncates it. NaN where the differences do not rise.
double edge_spread(const cv::Mat& g, cv::Point2d p, cv::Point2d n, double w) {
  constexpr double h = 0.25;
  const int m = static_cast<int>(std::ceil(w / h));
  double sum_g = 0.0, sum_sg = 0.0, sum_ssg = 0.0;
  double prev = sample_bilinear(g, p.x - m * h * n.x, p.y - m * h * n.y);
  for (int j = -m + 1; j <= m; ++j) {
    const double cur = sample_bilinear(g, p.x + j * h * n.x, p.y + j * h * n.y);
    const double d = cur - prev, s = (j - 0.5) * h;
    sum_g += d;
    sum_sg += d * s;
    sum_ssg += d * s * s;
    prev = cur;
  }
  if (!(sum_g > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double c = sum_sg / sum_g;
  return std::sqrt(std::max(0.0, sum_ssg / sum_g - c * c));
}

bool refine_edge_lines(const cv::Mat& g, std::array<cv::Point2d, 4>& c, int border_cells,
                       const io::Calibration* calib) {
  const double cell = min_side(c) / border_cells;
  if (cell < 1.5) return false;  // too small to sample the border reliably
  const double w = std::clamp(std::min(0.45 * cell, cell - 1.2), 1.0, 4.0);
  cv::Point2d centroid(0, 0);
  for (const auto& p : c) centroid += 0.25 * p;
  const bool undistort = calib && calib->has_distortion();
  std::array<cv::Vec4d, 4> lines;  // (vx, vy, x0, y0) in ideal (undistorted) pixels if undistort
  for (int k = 0; k < 4; ++k) {
    const cv::Point2d a = c[k], b = c[(k + 1) % 4];
    const double len = cv::norm(b - a);
    const cv::Point2d d = (b - a) / len;
    cv::Point2d n(d.y, -d.x);
    if (n.dot(0.5 * (a + b) - centroid) < 0) n = -n;  // outward: black inside, white outside
    const double skip = w + 1.5;
    std::vector<cv::Point2d> pts;
    for (double t = skip; t <= len - skip; t += 1.0) {
      const cv::Point2d p = a + t * d;
      double s = 0.0;
      if (edge_offset(g, p, n, w, s)) pts.push_back(p + s * n);
    }
    if (pts.size() < 4) return false;
    if (undistort) {
      std::vector<cv::Point2d> u;
      cv::undistortPoints(
          pts, u, cv::Mat(calib->K), calib->distortion(), cv::noArray(), cv::Mat(calib->K),
          cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 1e-10));
      pts.swap(u);
    }
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
    lines[static_cast<size_t>(k)] = cv::Vec4d(std::cos(theta), std::sin(theta), mean.x, mean.y);
  }
  std::array<cv::Point2d, 4> out;
  for (int k = 0; k < 4; ++k) {
    // corner k = intersection of edge k-1 (c[k-1] -> c[k]) and edge k (c[k] -> c[k+1])
    const cv::Vec4d& l1 = lines[static_cast<size_t>((k + 3) % 4)];
    const cv::Vec4d& l2 = lines[static_cast<size_t>(k)];
    const double det = l1[0] * (-l2[1]) - l1[1] * (-l2[0]);
    if (std::abs(det) < 1e-6) return false;
    const double rx = l2[2] - l1[2], ry = l2[3] - l1[3];
    const double t1 = (rx * (-l2[1]) - ry * (-l2[0])) / det;
    out[static_cast<size_t>(k)] = cv::Point2d(l1[2] + t1 * l1[0], l1[3] + t1 * l1[1]);
  }
  if (undistort) {
    std::vector<cv::Point2d> ideal(out.begin(), out.end()), xy;
    const cv::Matx33d Kinv = calib->K.inv();
    for (auto& p : ideal) {
      const cv::Vec3d q = Kinv * cv::Vec3d(p.x, p.y, 1.0);
      xy.emplace_back(q[0] / q[2], q[1] / q[2]);
    }
    const auto px = io::denormalize_points(xy, *calib);
    std::copy(px.begin(), px.end(), out.begin());
  }
  const double max_move = std::max(1.5, 0.5 * cell);
  for (int k = 0; k < 4; ++k)
    if (!(cv::norm(out[static_cast<size_t>(k)] - c[static_cast<size_t>(k)]) <= max_move))
      return false;  // implausible: keep libapriltag's corners
  c = out;
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

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
  const double hi = v[h];
  if (v.size() % 2) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h)));
}

/// Offsets r_i of the inner border edge measured at positions t_i along a side (cells): the
/// line r(t) = a + b t fitted to them (least squares, then again without the points further
/// than max(0.3 px, 3 robust sigmas) from it), evaluated at the first and the last measured
/// position; returns the one of larger magnitude. A side that is shifted or tilted against the
/// true border edge makes r constant or growing towards the wrong corner. Not extrapolated to
/// the corners: with 2x2 supersampled or aliased images a short stretch of edge carries up to
/// ~0.25 px of quantisation error, which extrapolation would amplify. With the points spanning
/// less than 2 cells, their median. NaN for fewer than 4 points.
double end_offset(const std::vector<double>& t, const std::vector<double>& r) {
  const size_t k = r.size();
  if (k < 4) return std::numeric_limits<double>::quiet_NaN();
  const auto [tmin, tmax] = std::minmax_element(t.begin(), t.end());
  if (*tmax - *tmin < 2.0) return median(r);
  std::vector<char> use(k, 1);
  double a = 0.0, b = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    double s0 = 0, st = 0, stt = 0, sr = 0, str = 0;
    for (size_t i = 0; i < k; ++i)
      if (use[i]) {
        s0 += 1, st += t[i], stt += t[i] * t[i], sr += r[i], str += t[i] * r[i];
      }
    const double det = s0 * stt - st * st;
    if (s0 < 3 || !(det > 1e-9)) break;
    b = (s0 * str - st * sr) / det;
    a = (sr - b * st) / s0;
    std::vector<double> res(k);
    for (size_t i = 0; i < k; ++i) res[i] = std::abs(r[i] - a - b * t[i]);
    const double cut = std::max(0.3, 3.0 * 1.4826 * median(res));
    for (size_t i = 0; i < k; ++i) use[i] = res[i] <= cut;
  }
  const double r0 = a + b * *tmin, r1 = a + b * *tmax;
  return std::abs(r0) >= std::abs(r1) ? r0 : r1;
}

bool inside(const cv::Mat& g, cv::Point2d p) {
  return p.x >= 0.0 && p.y >= 0.0 && p.x <= g.cols - 1.0 && p.y <= g.rows - 1.0;
}

/// Object square in cell units -> image pixels: the homography of the corners, in undistorted
/// (ideal) pixels when the calibration has distortion, then re-distorted.
class SquareToImage {
 public:
  SquareToImage(const std::array<cv::Point2d, 4>& corners, int n, const io::Calibration* calib)
      : calib_(calib && calib->has_distortion() ? calib : nullptr) {
    std::vector<cv::Point2d> ideal(corners.begin(), corners.end());
    if (calib_) {
      ideal = io::normalize_points(ideal, *calib_);
      for (auto& p : ideal) {
        const cv::Vec3d q = calib_->K * cv::Vec3d(p.x, p.y, 1.0);
        p = cv::Point2d(q[0] / q[2], q[1] / q[2]);
      }
    }
    // Corner k of the object square in cell coordinates (X right, Y down the printed tag,
    // the black square is [0, n]^2): c0 bottom-left, c1 bottom-right, c2 top-right, c3 top-left.
    const double N = n;
    const double src[4][2] = {{0, N}, {N, N}, {N, 0}, {0, 0}};
    // H with h33 = 1 from the four correspondences (8 x 8 linear system, in double).
    cv::Matx<double, 8, 8> A;
    cv::Matx<double, 8, 1> b;
    for (int k = 0; k < 4; ++k) {
      const double x = src[k][0], y = src[k][1];
      const double u = ideal[static_cast<size_t>(k)].x, v = ideal[static_cast<size_t>(k)].y;
      const double r0[8] = {x, y, 1, 0, 0, 0, -x * u, -y * u};
      const double r1[8] = {0, 0, 0, x, y, 1, -x * v, -y * v};
      for (int j = 0; j < 8; ++j) {
        A(2 * k, j) = r0[j];
        A(2 * k + 1, j) = r1[j];
      }
      b(2 * k) = u;
      b(2 * k + 1) = v;
    }
    cv::Matx<double, 8, 1> h;
    ok_ = cv::solve(A, b, h, cv::DECOMP_LU);
    for (int j = 0; j < 8; ++j) H_(j / 3, j % 3) = h(j);
    H_(2, 2) = 1.0;
  }
  bool ok() const { return ok_; }
  std::vector<cv::Point2d> map(const std::vector<cv::Point2d>& obj) const {
    std::vector<cv::Point2d> out;
    out.reserve(obj.size());
    for (const auto& p : obj) {
      const cv::Vec3d q = H_ * cv::Vec3d(p.x, p.y, 1.0);
      out.emplace_back(q[0] / q[2], q[1] / q[2]);
    }
    if (calib_) {
      const cv::Matx33d Kinv = calib_->K.inv();
      for (auto& p : out) {
        const cv::Vec3d q = Kinv * cv::Vec3d(p.x, p.y, 1.0);
        p = cv::Point2d(q[0] / q[2], q[1] / q[2]);
      }
      out = io::denormalize_points(out, *calib_);
    }
    return out;
  }

 private:
  const io::Calibration* calib_;
  cv::Matx33d H_ = cv::Matx33d::zeros();
  bool ok_ = false;
};

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

const char* to_string(TargetStatus s) {
  switch (s) {
    case TargetStatus::detected:
      return "detected";
    case TargetStatus::not_found:
      return "not_found";
    case TargetStatus::duplicate_id:
      return "duplicate_id";
    case TargetStatus::low_margin:
      return "low_margin";
    case TargetStatus::high_hamming:
      return "high_hamming";
    case TargetStatus::border_mismatch:
      return "border_mismatch";
    case TargetStatus::no_image:
      return "no_image";
  }
  return "?";
}

TargetStatus parse_target_status(const std::string& token) {
  for (TargetStatus s : kAllTargetStatuses)
    if (token == to_string(s)) return s;
  std::string all;
  for (TargetStatus s : kAllTargetStatuses)
    all += (all.empty() ? "" : ", ") + std::string(to_string(s));
  throw InputError("unknown target status '" + token + "' (expected one of " + all + ")");
}

cv::Mat tag_pattern(const std::string& family, int id) {
  const render::TagFamily* f = render::find_tag_family(family);
  if (!f) throw InputError("unsupported tag family '" + family + "'");
  apriltag_family_t* fam = f->create();
  cv::Mat out;
  if (id >= 0 && static_cast<uint32_t>(id) < fam->ncodes) {
    image_u8_t* im = apriltag_to_image(fam, id);
    out = cv::Mat(im->height, im->width, CV_8UC1);
    for (int r = 0; r < im->height; ++r)
      for (int c = 0; c < im->width; ++c) out.at<uchar>(r, c) = im->buf[r * im->stride + c];
    // libapriltag 3.3 does not export image_u8_destroy; it is free(buf) + free(im).
    std::free(im->buf);
    std::free(im);
  }
  f->destroy(fam);
  return out;
}

BorderCheck check_border(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners,
                         const cv::Mat& pattern, int border_cells, const DetectorSettings& s,
                         const io::Calibration* calib) {
  CV_Assert(gray.type() == CV_8UC1);
  BorderCheck out;
  const int n = border_cells;
  if (pattern.empty() || n < 3 || pattern.rows != pattern.cols || pattern.rows < n + 2) return out;
  const int off = (pattern.rows - n) / 2;    // bitmap index of the black square's first cell
  auto white_at = [&](double X, double Y) {  // object cell coordinates -> bitmap colour
    const int c = static_cast<int>(std::floor(X)) + off, r = static_cast<int>(std::floor(Y)) + off;
    return pattern.at<uchar>(r, c) > 127;
  };
  // Only for a black border ring inside a white ring (not the reversed-border families).
  for (int i = 0; i < n; ++i)
    if (white_at(i + 0.5, 0.5) || white_at(0.5, i + 0.5) || white_at(i + 0.5, n - 0.5) ||
        white_at(n - 0.5, i + 0.5) || !white_at(i + 0.5, -0.5) || !white_at(-0.5, i + 0.5) ||
        !white_at(i + 0.5, n + 0.5) || !white_at(n + 0.5, i + 0.5))
      return out;
  const SquareToImage map(corners, n, calib);
  if (!map.ok()) return out;
  out.checked = true;

  // Side k runs from corner k to corner k+1: start S, direction D, outward normal O (cells).
  const double N = n;
  const cv::Point2d S[4] = {{0, N}, {N, N}, {N, 0}, {0, 0}};
  const cv::Point2d D[4] = {{1, 0}, {0, -1}, {-1, 0}, {0, 1}};
  const cv::Point2d O[4] = {{0, 1}, {1, 0}, {0, -1}, {-1, 0}};
  constexpr int kPerCell = 4;  // contrast samples per cell along a side
  const int m = kPerCell * n;  // contrast samples per side
  constexpr double kThicknessT[] = {0.2, 0.35, 0.5, 0.65, 0.8};  // along a white data cell

  // Every object point, mapped in one batch: white data cell centres, then per side its
  // contrast pairs (quiet zone, border) and its inner-edge triples (edge, outer, inner).
  std::vector<cv::Point2d> obj;
  std::vector<cv::Point2d> white_cells;
  for (int r = 1; r < n - 1; ++r)
    for (int c = 1; c < n - 1; ++c)
      if (white_at(c + 0.5, r + 0.5)) white_cells.emplace_back(c + 0.5, r + 0.5);
  if (white_cells.empty()) {
    out.checked = false;
    return out;
  }
  obj.insert(obj.end(), white_cells.begin(), white_cells.end());
  std::array<std::vector<double>, 4> edge_t;  // positions along side k of inner-edge points
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < m; ++j) {
      const cv::Point2d p = S[k] + ((j + 0.5) / kPerCell) * D[k];
      obj.push_back(p + 0.5 * O[k]);
      obj.push_back(p - 0.5 * O[k]);
    }
    for (int i = 1; i < n - 1; ++i) {
      const cv::Point2d centre = S[k] + (i + 0.5) * D[k] - 1.5 * O[k];
      if (!white_at(centre.x, centre.y)) continue;
      for (double t : kThicknessT) {
        const cv::Point2d e = S[k] + (i + t) * D[k] - 1.0 * O[k];
        edge_t[static_cast<size_t>(k)].push_back(i + t);
        obj.push_back(e);
        obj.push_back(e + 0.5 * O[k]);
        obj.push_back(e - 0.5 * O[k]);
      }
    }
  }
  const std::vector<cv::Point2d> img = map.map(obj);
  size_t at = 0;
  std::vector<double> white_level(white_cells.size());
  for (size_t i = 0; i < white_cells.size(); ++i) {
    const cv::Point2d p = img[at++];
    white_level[i] = inside(gray, p) ? sample_bilinear(gray, p.x, p.y)
                                     : std::numeric_limits<double>::quiet_NaN();
  }
  std::vector<double> all_white;
  for (double w : white_level)
    if (!std::isnan(w)) all_white.push_back(w);
  const double global_white = median(all_white);

  // Pixels whose centre lies within 0.5 px of a side: in an image integrated over the pixel
  // area (a camera, a supersampled rendering, any blur) those the edge crosses have
  // intermediate values (14-99 % of them on the rendered and synthesized tags); in a
  // point-sampled (aliased) image, such as a 1-sample-per-pixel rendering, none do (0-5 %), and
  // every edge position is quantised to the pixel grid by up to 0.5 px, so the border's two
  // edges may disagree by up to 1 px on a correct quad.
  int near_side = 0, intermediate = 0;
  std::vector<double> near, offsets, ts, spreads;
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    // Contrast samples.
    int failed = 0, outside = 0;
    for (int j = 0; j < m; ++j) {
      const cv::Point2d q = img[at++], b = img[at++];
      const cv::Point2d b_obj = S[k] + ((j + 0.5) / kPerCell) * D[k] - 0.5 * O[k];
      near.clear();
      for (size_t i = 0; i < white_cells.size(); ++i)
        if (!std::isnan(white_level[i]) && cv::norm(white_cells[i] - b_obj) <= 2.5)
          near.push_back(white_level[i]);
      const double white = near.empty() ? global_white : median(near);
      const bool in_image = inside(gray, q) && inside(gray, b);
      outside += !in_image;
      bool pass = in_image && !std::isnan(white);
      if (pass) {
        const double vq = sample_bilinear(gray, q.x, q.y), vb = sample_bilinear(gray, b.x, b.y);
        pass = white - vb > 0.0 && vq - vb >= s.border_min_contrast * (white - vb);
        const double len = cv::norm(q - b);
        if (pass && len > 0.0) {
          const cv::Point2d mid = 0.5 * (q + b), n = (q - b) / len;
          const int cx = cvRound(mid.x), cy = cvRound(mid.y);
          for (int y = cy - 1; y <= cy + 1; ++y)
            for (int x = cx - 1; x <= cx + 1; ++x) {
              if (x < 0 || y < 0 || x >= gray.cols || y >= gray.rows) continue;
              if (std::abs((cv::Point2d(x, y) - mid).dot(n)) > 0.5) continue;
              const double f = (gray.at<uchar>(y, x) - vb) / (vq - vb);
              ++near_side;
              intermediate += f >= 0.15 && f <= 0.85;
            }
        }
      }
      failed += !pass;
    }
    out.samples[ks] = m;
    out.failed[ks] = failed;
    out.outside[ks] = outside;
    // Inner edge of the border next to white data cells.
    offsets.clear();
    ts.clear();
    for (size_t i = 0; i < edge_t[ks].size(); ++i) {
      const cv::Point2d e = img[at++], outer = img[at++], inner = img[at++];
      const double cell = cv::norm(inner - outer);  // one cell across the edge, in pixels
      if (!(cell > 0.0)) continue;
      const cv::Point2d nin = (inner - outer) / cell;  // inward: border (dark) -> data (bright)
      const double w = std::clamp(std::min(0.45 * cell, cell - 1.2), 1.0, 4.0);
      if (!inside(gray, e - 1.2 * cell * nin) || !inside(gray, e + 1.2 * cell * nin)) continue;
      // Sub-pixel step near the expected position, kept only where the centroid in half the
      // window agrees to 0.2 px: another edge in the window (a shadow boundary running along
      // the border) pulls the wide centroid more.
      auto clean_step = [&](double from, double win, double& s_out) {
        double sw = 0.0, sh = 0.0;
        if (!edge_offset(gray, e + from * nin, nin, win, sw)) return false;
        if (!edge_offset(gray, e + (from + sw) * nin, nin, std::max(1.0, 0.5 * win), sh) ||
            std::abs(sh) > 0.2)
          return false;
        s_out = from + sw;
        return true;
      };
      double sv = 0.0;
      if (!clean_step(0.0, w, sv)) {
        // A quad off by more than the window: the steepest dark-to-bright rise within 0.8
        // cell, measured with a window that stays clear of the fitted side (one cell out).
        const double reach = 0.8 * cell;
        double best = 0.0, start = 0.0;
        for (double x = -reach; x <= reach; x += 0.25) {
          const cv::Point2d a = e + (x - 0.5) * nin, b = e + (x + 0.5) * nin;
          const double rise = sample_bilinear(gray, b.x, b.y) - sample_bilinear(gray, a.x, a.y);
          if (rise > best) best = rise, start = x;
        }
        const double win = std::clamp(start + cell - 1.0, 1.0, w);
        if (!clean_step(start, win, sv)) continue;
      }
      offsets.push_back(sv);
      ts.push_back(edge_t[ks][i]);
      const double spread = edge_spread(gray, e + sv * nin, nin, 0.5 * cell);
      if (!std::isnan(spread)) spreads.push_back(spread);
    }
    out.thickness_error[ks] = end_offset(ts, offsets);
  }
  out.aliased = near_side >= 16 && intermediate < 0.1 * near_side;
  out.thickness_limit = s.border_max_thickness_error + (out.aliased ? 0.5 : 0.0);

  // A camera's tone curve moves every edge of a blurred print alike: gamma encoding puts a
  // blurred edge a fraction of the blur toward the dark side (0.42 sigma per edge for sRGB and
  // black ink at 5 % of the white), so a correct border looks thinner on all four sides. The
  // thinning that every side shares (at least 3, and every side with a white data cell next to
  // it measured), that of the least thin side, is discounted up to border_blur_allowance x the
  // measured blur. A side on an occluder's outline
  // is thinner alone (or with its neighbour, towards one corner): the other sides do not share
  // its error, so it is judged as before. A border thicker on every side is not discounted.
  const double spread = median(spreads);
  out.edge_blur = std::isnan(spread) ? 0.0 : std::sqrt(std::max(0.0, spread * spread - 0.25));
  {
    int planned = 0, measured = 0, thinner = 0;
    double least = -std::numeric_limits<double>::infinity();  // the least thin side
    for (size_t k = 0; k < 4; ++k) {
      const double t = out.thickness_error[k];
      planned += edge_t[k].size() >= 4;
      if (std::isnan(t)) continue;
      ++measured;
      thinner += t < 0.0;
      least = std::max(least, t);
    }
    // Every side the bitmap lets us measure must have been measured: a side whose inner edge
    // is not found where one cell inside it should be (a side moved off the border) is no
    // evidence of a thinning shared by all sides.
    if (measured >= 3 && measured == planned && thinner == measured)
      out.common_offset = std::max(least, -s.border_blur_allowance * out.edge_blur);
  }

  // A side fails on either test; the reason names the side that fails worst (relative to its
  // threshold), which is the one on the occluder's outline when the others only inherit part
  // of its error through the homography.
  char buf[200];
  double worst = 0.0;  // how far the worst failing side exceeds its threshold (ratio)
  for (int k = 0; k < 4; ++k) {
    const size_t ks = static_cast<size_t>(k);
    const int failed = out.failed[ks];
    const double contrast_excess =
        std::max(failed / std::max(1.0, s.border_max_failed_fraction * m),
                 out.outside[ks] > 0 ? 1.0 + static_cast<double>(out.outside[ks]) / m : 0.0);
    const double thickness_excess =
        std::isnan(out.thickness_error[ks])
            ? 0.0
            : std::abs(out.thickness_error[ks] - out.common_offset) / out.thickness_limit;
    // A quiet zone cut by the image border cannot be verified: a tag is only accepted with its
    // quiet zone in the image (else a partly visible neighbour, e.g. on another face of a cube,
    // could pass and hide the target as a duplicate).
    const bool contrast_fails = failed > s.border_max_failed_fraction * m || out.outside[ks] > 0;
    const bool thickness_fails = thickness_excess > 1.0;
    if (!contrast_fails && !thickness_fails) continue;
    out.ok = false;
    const double excess =
        std::max(contrast_fails ? contrast_excess : 0.0, thickness_fails ? thickness_excess : 0.0);
    if (excess <= worst) continue;
    worst = excess;
    if (out.outside[ks] > 0 && (!thickness_fails || contrast_excess >= thickness_excess))
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): quiet zone outside the image at %d of %d samples", k,
                    k, (k + 1) % 4, out.outside[ks], m);
    else if (contrast_fails && (!thickness_fails || contrast_excess >= thickness_excess))
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): quiet zone not brighter than the border at %d of "
                    "%d samples",
                    k, k, (k + 1) % 4, failed, m);
    else if (out.common_offset == 0.0)
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): black border %.2f px %s than one cell", k, k,
                    (k + 1) % 4, std::abs(out.thickness_error[ks]),
                    out.thickness_error[ks] < 0 ? "thinner" : "thicker");
    else
      std::snprintf(buf, sizeof buf,
                    "side %d (corners %d-%d): black border %.2f px %s than one cell (%.2f px "
                    "of it on every side discounted for blur)",
                    k, k, (k + 1) % 4, std::abs(out.thickness_error[ks]),
                    out.thickness_error[ks] < 0 ? "thinner" : "thicker",
                    std::abs(out.common_offset));
    out.reason = buf;
  }
  return out;
}

void refine_corners(const cv::Mat& gray, std::array<cv::Point2d, 4>& corners, Refinement mode,
                    int border_cells, const io::Calibration* calib) {
  CV_Assert(gray.type() == CV_8UC1);
  switch (mode) {
    case Refinement::none:
      return;
    case Refinement::corner_subpix:
      refine_subpix(gray, corners, border_cells);
      return;
    case Refinement::edge_lines:
      refine_edge_lines(gray, corners, border_cells, calib);
      return;
  }
}

struct TagDetector::Impl {
  DetectorSettings s;
  render::TagFamilyPtr family{nullptr, nullptr};
  apriltag_detector_t* td = nullptr;
  cv::Mat gray;                   // conversion buffer for non-gray input
  cv::Mat normalized;             // the image with the searched region normalised (SearchOptions)
  std::vector<cv::Mat> patterns;  // bitmap of each tag of the body, for the border check

  explicit Impl(DetectorSettings settings) : s(std::move(settings)) {
    validate(s);
    family = render::create_tag_family(s.family);
    td = apriltag_detector_create();
    if (!td) throw std::runtime_error("libapriltag: cannot create the detector");
    apriltag_detector_add_family_bits(td, family.get(), s.bits_corrected);
    td->quad_decimate = static_cast<float>(s.quad_decimate);
    td->quad_sigma = static_cast<float>(s.quad_sigma);
    td->nthreads = s.nthreads;
    td->refine_edges = s.refine_edges;
    td->decode_sharpening = s.decode_sharpening;
    td->qtp.min_white_black_diff = s.min_white_black_diff;
    td->debug = false;
    patterns.push_back(tag_pattern(s.family, s.target_id));
    for (int id : s.bundle_ids) patterns.push_back(tag_pattern(s.family, id));
  }
  ~Impl() {
    if (td) apriltag_detector_destroy(td);  // before the family it holds
  }
};

namespace {

// The tags of each target: DetectorSettings::tags_per_target, or all of them as one.
std::vector<TargetDecision> target_ranges(const DetectorSettings& s) {
  std::vector<TargetDecision> t;
  if (s.tags_per_target.empty()) {
    t.push_back({TargetStatus::not_found, "", 0, 1 + s.bundle_ids.size()});
    return t;
  }
  size_t first = 0;
  for (int c : s.tags_per_target) {
    t.push_back({TargetStatus::not_found, "", first, static_cast<size_t>(c)});
    first += static_cast<size_t>(c);
  }
  return t;
}

// A region that was not searched: every target not found (their tags' ids in the reason).
FrameDetections not_searched(FrameDetections out, const DetectorSettings& s) {
  out.targets = target_ranges(s);
  for (auto& t : out.targets) {
    const int id = t.first_tag == 0 ? s.target_id : s.bundle_ids[t.first_tag - 1];
    t.reason = "id " + std::to_string(id) + " not decoded";
  }
  return out;
}

// Each target's status and reason from its tags' decisions: a single tag's own; a bundle is
// `detected` when at least one of its tags is, else the status and reason of the tag that got
// furthest (duplicate_id, then border_mismatch, low_margin, high_hamming; the primary first on
// ties), prefixed by `tag <id>: `, or `ids 0, 1 not decoded (...)` when none was decoded.
void decide_targets(FrameDetections& out, const DetectorSettings& s) {
  const auto rank = [](TargetStatus st) {
    switch (st) {
      case TargetStatus::detected:
        return 5;
      case TargetStatus::duplicate_id:
        return 4;
      case TargetStatus::border_mismatch:
        return 3;
      case TargetStatus::low_margin:
        return 2;
      case TargetStatus::high_hamming:
        return 1;
      default:
        return 0;
    }
  };
  out.targets = target_ranges(s);
  for (TargetDecision& target : out.targets) {
    const auto begin = out.tags.begin() + static_cast<long>(target.first_tag);
    const auto end = begin + static_cast<long>(target.tag_count);
    if (target.tag_count == 1) {  // a single tag: its decision is the target's
      target.status = begin->status;
      target.reason = begin->reason;
      continue;
    }
    auto best = begin;
    for (auto t = begin; t != end; ++t)
      if (rank(t->status) > rank(best->status)) best = t;
    target.status = best->status;
    if (best->status == TargetStatus::detected) {
      target.reason.clear();
    } else if (best->status != TargetStatus::not_found) {
      target.reason = "tag " + std::to_string(best->id) + ": " + best->reason;
    } else {
      std::string ids;
      for (auto t = begin; t != end; ++t) ids += (ids.empty() ? "" : ", ") + std::to_string(t->id);
      target.reason = "ids " + ids + " not decoded (" + std::to_string(out.all.size()) +
                      " other tag(s) decoded)";
    }
  }
  out.status = out.targets[0].status;
  out.reason = out.targets[0].reason;
}

}  // namespace

TagDetector::TagDetector(DetectorSettings settings)
    : impl_(std::make_unique<Impl>(std::move(settings))) {}
TagDetector::~TagDetector() = default;
TagDetector::TagDetector(TagDetector&&) noexcept = default;
TagDetector& TagDetector::operator=(TagDetector&&) noexcept = default;

const DetectorSettings& TagDetector::settings() const {
  return impl_->s;
}
int TagDetector::border_cells() const {
  return impl_->family->width_at_border;
}

FrameDetections TagDetector::detect(const cv::Mat& image, const io::Calibration* calib) {
  return detect(image, cv::Rect(0, 0, image.cols, image.rows), calib);
}

cv::Mat normalize_illumination(const cv::Mat& gray, int window) {
  CV_Assert(gray.type() == CV_8UC1 && window >= 1);
  const cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(window, window));
  cv::Mat white;
  cv::morphologyEx(gray, white, cv::MORPH_CLOSE, k, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  const int smooth = std::max(1, window / 4);
  cv::blur(white, white, cv::Size(smooth, smooth), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  cv::Mat white_f, gray_f, out;
  white.convertTo(white_f, CV_32F);
  cv::max(white_f, 8.0, white_f);  // no division by (near) zero in black areas
  gray.convertTo(gray_f, CV_32F);
  cv::divide(gray_f, white_f, gray_f, 240.0);
  gray_f.convertTo(out, CV_8U);  // saturates
  return out;
}

FrameDetections TagDetector::detect(const cv::Mat& image, const cv::Rect& region,
                                    const io::Calibration* calib, const SearchOptions& opt) {
  const cv::Mat* g = &image;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, impl_->gray, cv::COLOR_BGR2GRAY);
    g = &impl_->gray;
  } else if (image.type() != CV_8UC1) {
    throw std::invalid_argument("TagDetector::detect: expected an 8-bit gray or BGR image");
  }
  const DetectorSettings& s = impl_->s;
  FrameDetections out;
  char buf[200];
  std::snprintf(buf, sizeof buf, "id %d not decoded", s.target_id);
  out.reason = buf;
  if (g->empty()) return not_searched(std::move(out), s);
  if (!(opt.decimate == 0.0 || opt.decimate >= 1.0))
    throw std::invalid_argument("TagDetector::detect: decimate must be 0 or >= 1");
  if (opt.normalized && opt.normalize_window < 1)
    throw std::invalid_argument("TagDetector::detect: normalize_window must be >= 1");
  const double decimate = opt.decimate > 0.0 ? opt.decimate : s.quad_decimate;
  // Align the region to the decimation grid so a windowed search samples the same pixels as a
  // full-frame one (identical quads, identical corners).
  // libapriltag thresholds in 4x4 tiles of the decimated image: align to 4 x decimate.
  const int step = 4 * std::max(1, static_cast<int>(std::ceil(decimate)));
  cv::Rect aligned = region;
  aligned.x -= ((aligned.x % step) + step) % step;
  aligned.y -= ((aligned.y % step) + step) % step;
  aligned.width += region.x - aligned.x;
  aligned.height += region.y - aligned.y;
  const cv::Rect roi = aligned & cv::Rect(0, 0, g->cols, g->rows);
  // Nothing decodable in a tiny region; libapriltag needs a few tiles.
  if (roi.width < 16 || roi.height < 16) return not_searched(std::move(out), s);
  // libapriltag searches the region only (a view into the image, no copy, or its normalised
  // normalised copy); corners are mapped back to the whole image and refined there.
  const cv::Mat sub =
      opt.normalized ? normalize_illumination((*g)(roi), opt.normalize_window) : (*g)(roi);
  const cv::Mat* original = g;
  if (opt.normalized) {
    // Refinement and border check on the normalised region too: a shadow edge along a border
    // edge biases the edge fit on the image itself.
    g->copyTo(impl_->normalized);
    sub.copyTo(impl_->normalized(roi));
    g = &impl_->normalized;
  }
  image_u8_t im{sub.cols, sub.rows, static_cast<int32_t>(sub.step[0]),
                const_cast<uint8_t*>(sub.ptr<uint8_t>())};
  impl_->td->quad_decimate = static_cast<float>(decimate);
  zarray_t* dets = apriltag_detector_detect(impl_->td, &im);
  impl_->td->quad_decimate = static_cast<float>(s.quad_decimate);
  if (!dets) throw std::runtime_error("libapriltag: detection failed");
  for (int i = 0; i < zarray_size(dets); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(dets, i, &det);
    TagDetection d;
    d.id = det->id;
    d.hamming = det->hamming;
    d.margin = det->decision_margin;
    for (int k = 0; k < 4; ++k)
      d.corners[static_cast<size_t>(k)] = cv::Point2d(det->p[k][0] - kApriltagPixelOffset + roi.x,
                                                      det->p[k][1] - kApriltagPixelOffset + roi.y);
    d.center = cv::Point2d(det->c[0] - kApriltagPixelOffset + roi.x,
                           det->c[1] - kApriltagPixelOffset + roi.y);
    out.all.push_back(d);
  }
  apriltag_detections_destroy(dets);

  // Target decision, per tag of the body. Every detection of the tag's id that passes hamming
  // and margin is refined and border-checked; the duplicate-id rule counts only those that
  // pass, so a partly visible second tag of the same id (a neighbouring face of a cube, a tag
  // cut by the image border) does not hide a good one. Without a passing one, the reason is the
  // furthest any candidate got: border check, then margin, then hamming.
  auto decide = [&](int tag_id, const cv::Mat& pattern) {
    TagDecision dec;
    dec.id = tag_id;
    int n_id = 0, n_hamming_ok = 0, n_margin_ok = 0, n_passed = 0, passed = -1;
    double best_margin = -1.0;
    int best_hamming = 1 << 30;
    std::string border_reason;
    for (size_t i = 0; i < out.all.size(); ++i) {
      TagDetection& d = out.all[i];
      if (d.id != tag_id) continue;
      ++n_id;
      best_hamming = std::min(best_hamming, d.hamming);
      if (d.hamming > s.max_hamming) continue;
      ++n_hamming_ok;
      best_margin = std::max(best_margin, d.margin);
      if (d.margin < s.min_decision_margin) continue;
      ++n_margin_ok;
      std::array<cv::Point2d, 4> corners = d.corners;
      refine_corners(*g, corners, s.refinement, border_cells(), calib);
      BorderCheck bc = s.border_check ? check_border(*g, corners, pattern, border_cells(), s, calib)
                                      : BorderCheck{};
      if (bc.ok && opt.normalized) {
        // Corners must not depend on the illumination correction: where a shadow boundary runs
        // along a border edge, the fits on the image and on its normalised copy disagree.
        std::array<cv::Point2d, 4> plain = d.corners;
        refine_corners(*original, plain, s.refinement, border_cells(), calib);
        double moved = 0.0;
        for (size_t k = 0; k < 4; ++k) moved = std::max(moved, cv::norm(plain[k] - corners[k]));
        if (moved > kMaxNormalizedDisagreement) {
          bc.ok = false;
          std::snprintf(buf, sizeof buf,
                        "shadow edge along the border: corners fitted on the image and on its "
                        "normalised copy differ by %.2f px",
                        moved);
          bc.reason = buf;
        }
      }
      if (!bc.ok) {
        if (border_reason.empty()) border_reason = bc.reason;
        continue;
      }
      d.corners = corners;  // only a passing candidate's corners are replaced by refined ones
      ++n_passed;
      passed = static_cast<int>(i);
    }
    if (n_passed > 1) {
      dec.status = TargetStatus::duplicate_id;
      std::snprintf(
          buf, sizeof buf,
          "%d detections of id %d pass every check (more than one tag with the target id in view)",
          n_passed, tag_id);
    } else if (n_passed == 1) {
      dec.status = TargetStatus::detected;
      dec.index = passed;
      buf[0] = '\0';
    } else if (n_margin_ok > 0) {
      dec.status = TargetStatus::border_mismatch;
      std::snprintf(buf, sizeof buf, "%.*s", 190, border_reason.c_str());
    } else if (n_hamming_ok > 0) {
      dec.status = TargetStatus::low_margin;
      std::snprintf(buf, sizeof buf, "decision margin %.1f below %g", best_margin,
                    s.min_decision_margin);
    } else if (n_id > 0) {
      dec.status = TargetStatus::high_hamming;
      std::snprintf(buf, sizeof buf, "%d corrected bits, more than %d", best_hamming,
                    s.max_hamming);
    } else {
      std::snprintf(buf, sizeof buf, "id %d not decoded (%zu other tag(s) decoded)", tag_id,
                    out.all.size());
    }
    dec.reason = buf;
    return dec;
  };
  out.tags.push_back(decide(s.target_id, impl_->patterns[0]));
  for (size_t k = 0; k < s.bundle_ids.size(); ++k)
    out.tags.push_back(decide(s.bundle_ids[k], impl_->patterns[k + 1]));
  out.target_index = out.tags[0].index;
  decide_targets(out, s);
  return out;
}

}  // namespace netvmo::frontend
