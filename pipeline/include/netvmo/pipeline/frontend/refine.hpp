// Corner refinement: the stage after libapriltag's quad fit. OpenCV pixel convention and
// libapriltag's corner order (tag_detector.hpp).
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "netvmo/pipeline/frontend/detections.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

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
std::optional<CornerCovariance> refine_corners(const cv::Mat& gray,
                                               std::array<cv::Point2d, 4>& corners, Refinement mode,
                                               int border_cells,
                                               const io::Calibration* calib = nullptr);

}  // namespace netvmo::frontend
