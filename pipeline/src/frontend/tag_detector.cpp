#include "netvmo/pipeline/frontend/tag_detector.hpp"

#include <apriltag/apriltag.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::frontend {

namespace {

/// libapriltag reports pixel centres at +0.5 (measured, see tests/pipeline/test_detector.cpp).
constexpr double kApriltagPixelOffset = 0.5;

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
  if (!(s.min_decision_margin >= 0.0)) bad("min_decision_margin must be >= 0");
  if (s.max_hamming < 0) bad("max_hamming must be >= 0");
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
          pts, u, cv::Mat(calib->K), cv::Mat(calib->dist), cv::noArray(), cv::Mat(calib->K),
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
      return "not found";
    case TargetStatus::duplicate_id:
      return "duplicate id";
    case TargetStatus::low_margin:
      return "low decision margin";
    case TargetStatus::high_hamming:
      return "too many corrected bits";
  }
  return "?";
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
  cv::Mat gray;  // conversion buffer for non-gray input

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
  }
  ~Impl() {
    if (td) apriltag_detector_destroy(td);  // before the family it holds
  }
};

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

FrameDetections TagDetector::detect(const cv::Mat& image, const cv::Rect& region,
                                    const io::Calibration* calib) {
  const cv::Mat* g = &image;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, impl_->gray, cv::COLOR_BGR2GRAY);
    g = &impl_->gray;
  } else if (image.type() != CV_8UC1) {
    throw std::invalid_argument("TagDetector::detect: expected an 8-bit gray or BGR image");
  }
  FrameDetections out;
  if (g->empty()) return out;
  // Align the region to the decimation grid so a windowed search samples the same pixels as a
  // full-frame one (identical quads, identical corners).
  // libapriltag thresholds in 4x4 tiles of the decimated image: align to 4 x decimate.
  const int step = 4 * std::max(1, static_cast<int>(std::ceil(impl_->s.quad_decimate)));
  cv::Rect aligned = region;
  aligned.x -= ((aligned.x % step) + step) % step;
  aligned.y -= ((aligned.y % step) + step) % step;
  aligned.width += region.x - aligned.x;
  aligned.height += region.y - aligned.y;
  const cv::Rect roi = aligned & cv::Rect(0, 0, g->cols, g->rows);
  // Nothing decodable in a tiny region; libapriltag needs a few tiles.
  if (roi.width < 16 || roi.height < 16) return out;
  // libapriltag searches the region only (a view into the image, no copy); corners are mapped
  // back to the whole image and refined there.
  const cv::Mat sub = (*g)(roi);
  image_u8_t im{sub.cols, sub.rows, static_cast<int32_t>(sub.step[0]),
                const_cast<uint8_t*>(sub.ptr<uint8_t>())};
  zarray_t* dets = apriltag_detector_detect(impl_->td, &im);
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

  // Target decision: candidates with the target id that pass hamming and margin; exactly one.
  const DetectorSettings& s = impl_->s;
  int accepted = -1, n_accepted = 0;
  bool any_id = false, any_hamming_ok = false;
  for (size_t i = 0; i < out.all.size(); ++i) {
    const TagDetection& d = out.all[i];
    if (d.id != s.target_id) continue;
    any_id = true;
    if (d.hamming > s.max_hamming) continue;
    any_hamming_ok = true;
    if (d.margin < s.min_decision_margin) continue;
    accepted = static_cast<int>(i);
    ++n_accepted;
  }
  if (n_accepted > 1) {
    out.status = TargetStatus::duplicate_id;
  } else if (n_accepted == 1) {
    out.status = TargetStatus::detected;
    out.target_index = accepted;
    refine_corners(*g, out.all[static_cast<size_t>(accepted)].corners, s.refinement, border_cells(),
                   calib);
  } else if (!any_id) {
    out.status = TargetStatus::not_found;
  } else {
    out.status = any_hamming_ok ? TargetStatus::low_margin : TargetStatus::high_hamming;
  }
  return out;
}

}  // namespace netvmo::frontend
