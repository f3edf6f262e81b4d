// The frame check of a decoded tag's refined corners: does the quad frame a black border inside
// a white quiet zone, as the tag's bitmap says it must?
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>

#include "netvmo/pipeline/frontend/detector_settings.hpp"
#include "netvmo/pipeline/io/calibration.hpp"

namespace netvmo::frontend {

/// Result of check_border().
struct BorderCheck {
  bool checked = false;  ///< false: not applicable (reversed-border family), `ok` stays true
  bool ok = true;        ///< the corners frame a black border inside a white quiet zone
  std::string reason;    ///< the worst failing side and why (empty when ok)
  /// Per side (side k runs from corner k to corner k+1): contrast samples, and how many failed.
  std::array<int, 4> samples{}, failed{};
  /// Per side: contrast samples outside the image (any one fails the side: a quiet zone cut by
  /// the image border cannot be verified).
  std::array<int, 4> outside{};
  /// Per side: the larger offset of the inner edge of the black border from one cell inside
  /// the side, at the ends of the measured stretch [px], negative when the border looks
  /// thinner than one cell; NaN where fewer than 4 points were measured (no white data cell
  /// next to that side, or the steps were not clean).
  std::array<double, 4> thickness_error{};
  /// The image is point-sampled (aliased) along the sides: no pixel straddling a side has an
  /// intermediate value. Edge positions are then quantised to the pixel grid by up to 0.5 px.
  bool aliased = false;
  /// The limit the thickness errors were held to: border_max_thickness_error, plus 0.5 px
  /// when `aliased` (the border's two edges may then disagree by up to 1 px on a correct quad).
  double thickness_limit = 0.0;
  /// Gaussian sigma of the blur of the border's inner edges beyond the pixel's own [px]:
  /// sqrt(spread^2 - 0.25) of the median spread of the intensity differences across the
  /// measured inner-edge points (window +-0.5 cell; 0.25 px^2 is the spread of a sharp edge
  /// integrated over the pixel and interpolated bilinearly). The window truncates the spread,
  /// so heavy blur on small cells is underestimated (a smaller allowance). 0 when unmeasured.
  double edge_blur = 0.0;
  /// The offset discounted from every side's thickness error (<= 0): when all measured sides
  /// (at least 3, and every side with a white data cell next to it) look thinner, the error of
  /// the least thin one, but no lower than -border_blur_allowance x edge_blur; otherwise 0.
  double common_offset = 0.0;
};

/// The tag's bitmap as libapriltag prints it (apriltag_to_image): total_width x total_width
/// cells, 255 white / 0 black, row 0 at the top (+y) of the printed tag. Empty for an id
/// outside the family.
cv::Mat tag_pattern(const std::string& family, int id);

/// Border / quiet-zone consistency of the refined corners of a decoded tag whose bitmap is
/// `pattern` (tag_pattern()). The homography of the corners maps the object square (in bit
/// cells, the black square is [0, n]^2) to the image, in undistorted pixels when `calib` has
/// distortion (sample points are re-distorted). Along each side (side k runs from corner k to
/// corner k+1):
///  - contrast, every quarter cell: a quiet-zone sample half a cell outside the side and a
///    border sample half a cell inside (the centres of the white ring and of the black border
///    cell row). It passes when quiet - border >= border_min_contrast x (white - border), with
///    `white` the median of the tag's white data cells within 2.5 cells of the border sample:
///    a local level, so a shadow that darkens both sides of the edge scales both sides of the
///    inequality. The side fails when more than border_max_failed_fraction of its 4n samples
///    fail (an occluder darker than the quiet zone beyond the side, or corners more than half a
///    cell off), or when any sample lies outside the image (a quiet zone cut by the image
///    border cannot be verified; a partly visible tag must not pass, see TargetStatus).
///  - border thickness, where the data cell next to the border is white: the inner edge of the
///    border (the dark-to-bright step one cell inside the side) is located to sub-pixel at 5
///    points per such cell, by the centroid of the intensity differences along the normal as in
///    the edge refinement (window 0.45 cell, at most 4 px), kept only where the centroid in
///    half that window agrees to 0.2 px (no second edge, such as a shadow boundary, nearby).
///    A line through the offsets (robust least squares along the side) is evaluated at the
///    first and last measured point: the side's thickness error e_k (the one of larger
///    magnitude). A camera's tone curve moves every edge of a blurred print toward the dark
///    side, so a correct border looks thinner on all four sides: when at least 3 sides are
///    measured, every side with a white data cell next to it among them (a side whose inner edge
///    is not found is no evidence), and all are thinner (e_k < 0), the common offset c is the
///    error of the least thin one, but no lower than -border_blur_allowance x `edge_blur` (the
///    measured Gaussian blur of the inner edges beyond the pixel's own); otherwise c = 0 (a
///    border thicker on every side is not discounted). The side fails when
///    |e_k - c| > border_max_thickness_error (needs 4 points), 0.5 px more in a point-sampled
///    image (`aliased`). A side fitted to an occluder's outline that hides part of the border cell
///    row makes the border look thinner towards the wrong corner, whatever the occluder's
///    brightness; the other sides do not share that error, so c stays near 0.
/// Families without a black border ring inside a white one (tagStandard41h12, ...) are not
/// checked (`checked` false).
BorderCheck check_border(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners,
                         const cv::Mat& pattern, int border_cells, const DetectorSettings& s,
                         const io::Calibration* calib = nullptr);

}  // namespace netvmo::frontend
