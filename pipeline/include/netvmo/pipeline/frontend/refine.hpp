// Corner refinement: the stage after libapriltag's quad fit. OpenCV pixel convention and
// libapriltag's corner order (tag_detector.hpp).
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/detections.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// The sub-pixel samples of a quad's four outer edges that the edge-line fit used, one a pixel
/// along each side (pixels, as the image is; side k from corner k to corner k + 1), and the
/// same in ideal (undistorted) pixels where the calibration has distortion (else empty).
struct EdgeSamples {
  std::array<std::vector<cv::Point2d>, 4> sides, ideal;
};

/// Sub-pixel corner refinement applied (in OpenCV) to the target's corners after detection.
enum class Refinement {
  none,           ///< libapriltag's corners as they are (its refine_edges already fits edges)
  corner_subpix,  ///< cv::cornerSubPix, window scaled to the tag's cell size
  edge_lines,     ///< lines fitted to sub-pixel samples of the four outer border edges,
                  ///< intersected (in undistorted coordinates when a calibration is given)
};
const char* to_string(Refinement r);
/// "none", "subpix", "edges"; throws InputError otherwise.
Refinement parse_refinement(const std::string& name);

/// Refines the four corners of one detected quad in place (OpenCV). `border_cells` is the
/// number of bit cells across the black border square. Returns the corners' first-order
/// covariance from the edge fits when the edge lines were fitted and used (edge_lines; in ideal
/// pixels when the calibration has distortion, else in pixels): each edge's line has the
/// variances of its offset and angle that the scatter of its samples about it gives, the lines
/// are independent, and each corner moves with the two lines it is the intersection of (so
/// neighbouring corners, which share a line, are correlated). nullopt otherwise (none, subpix,
/// or a fit refused and libapriltag's corners kept). Exposed for tests and benchmarks.
/// `samples`, when given: the edge samples the edge lines were fitted to (EdgeSamples; empty
/// where no lines were fitted), for quad_bow().
std::optional<CornerCovariance> refine_corners(const cv::Mat& gray,
                                               std::array<cv::Point2d, 4>& corners, Refinement mode,
                                               int border_cells,
                                               const io::Calibration* calib = nullptr,
                                               EdgeSamples* samples = nullptr);

/// One side's outer edge against the straight line fitted to it: where a quadratic fitted to
/// the same samples (offset across the line against position along it) lies at the side's two
/// ends, along the line's normal [px; ideal pixels with distortion], with its standard error.
struct SideBow {
  std::array<double, 2> end_offset{};  ///< at corner k and at corner k + 1
  std::array<double, 2> end_se{};
  int samples = 0;
  double blur = 0.0;  ///< sigma of the outer edge's blur across the side [px]
  /// The quadratic itself (side_bow_at()): the outer edge lies coef[0] + coef[1] u + coef[2] u^2
  /// along `normal` from the straight line through `origin` along the unit `dir`, at
  /// u = (p - origin) . dir / half [ideal pixels].
  cv::Point2d origin, dir, normal;
  double half = 0.0;
  std::array<double, 3> coef{};
};

/// Where a side's bowed outer edge lies from its straight line, at the point of the line nearest
/// `p` (ideal pixels): the displacement along the line's normal. Zero for an unmeasured side.
cv::Point2d side_bow_at(const SideBow& side, const cv::Point2d& p);

/// The bow of a quad's four outer edges and where it puts the corners. A flat print imaged by a
/// pinhole camera (distortion removed) has straight sides; a bent card, or distortion that the
/// calibration leaves, bows them, and then the straight sides' intersections miss the
/// corners, where the bowed edges end. corner_shift[k]: from the straight sides' corner k to
/// where the two quadratics end (each side's end offset along its normal), in ideal pixels.
struct QuadBow {
  bool measured = false;  ///< false: cells below 1.5 px, fewer than 8 samples on a side
  std::array<SideBow, 4> sides;
  std::array<cv::Point2d, 4> corner_shift{};
  std::array<double, 4> corner_se{};  ///< standard error of |corner_shift| along it
};
/// Measured on the samples of the edge-line fit (refine_corners, edges), with two limits where a
/// flat tag's sides would look bowed: every side's blur sigma is measured across its outer edge
/// (SideBow::blur), and the bow is not measured where the border's inner edge, one cell in, lies
/// within 3 sigma + 0.5 px of the window across the outer edge (the data cells next to the
/// border, white at some and black at others, then move the samples), nor from samples nearer a
/// corner than (3 sigma + 1 px) / sin(corner's angle) of the other side (at most a quarter of the
/// side), whose blurred edge pulls them inward.
/// `samples`: the edge-line fit's own samples (refine_corners()), else the sides are sampled
/// here (about 40 samples a side).
QuadBow quad_bow(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners, int border_cells,
                 const io::Calibration* calib = nullptr, const EdgeSamples* samples = nullptr);

}  // namespace netvmo::frontend
