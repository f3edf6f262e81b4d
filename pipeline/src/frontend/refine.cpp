#include "netvmo/pipeline/frontend/refine.hpp"

#include <opencv2/imgproc.hpp>

#include "netvmo/pipeline/error.hpp"
#include "sampling.hpp"

namespace netvmo::frontend {

namespace {

using detail::edge_offset;
using detail::min_side;

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
    lines[static_cast<size_t>(k)] = cv::Vec4d(std::cos(theta), std::sin(theta), mean.x, mean.y);
  }
  std::array<cv::Point2d, 4> out;
  for (int k = 0; k < 4; ++k) {
    // corner k = intersection of edge k-1 (c[k-1] -> c[k]) and edge k (c[k] -> c[k+1])
    const cv::Vec4d& l1 = lines[static_cast<size_t>((k + 3) % 4)];
    const cv::Vec4d& l2 = lines[static_cast<size_t>(k)];
    const auto corner =
        detail::intersect_lines({l1[2], l1[3]}, {l1[0], l1[1]}, {l2[2], l2[3]}, {l2[0], l2[1]});
    if (!corner) return false;
    out[static_cast<size_t>(k)] = *corner;
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

}  // namespace netvmo::frontend
