// The frame check of a decoded tag's refined corners: does the quad frame a black border inside
// a white quiet zone, as the tag's bitmap says it must?
#pragma once

#include <array>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "netvmo/pipeline/frontend/detector_settings.hpp"
#include "netvmo/pipeline/frontend/refine.hpp"
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
  /// Per side, the limit its error after the print's model is held to: thickness_limit, or
  /// border_scatter_allowance x edge_bias_scatter across the side where that is larger.
  std::array<double, 4> side_limit{};
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
  /// The print's edge bias along the tag's X and Y axes [px]: how far every black/white edge
  /// of the print is imaged toward the white (> 0: the black looks larger, as with ink spread
  /// or bloom around bright paper; < 0: smaller, as a camera's tone curve makes a blurred edge,
  /// about 0.42 sigma per edge). Measured on the tag's own data cells (only with
  /// DetectorSettings::border_edge_bias): along each data row (X) and column (Y), each pair of
  /// adjacent runs of white and black cells between interior transitions gives one estimate
  /// with the local scale error eliminated (check_border()); the median of an axis's
  /// estimates, NaN where it has fewer than 4. The test uses their local values.
  std::array<double, 2> edge_bias{std::numeric_limits<double>::quiet_NaN(),
                                  std::numeric_limits<double>::quiet_NaN()};
  std::array<int, 2> edge_bias_pairs{};  ///< the estimates behind edge_bias
  /// Their robust scatter [px]: 1.4826 x the median absolute deviation from edge_bias, how
  /// sharply this image shows the print's edges (0.03 px on a clean rendering).
  std::array<double, 2> edge_bias_scatter{};
  /// The standard deviation of one transition's measured offset on each axis, from the scatter
  /// of the axis's estimates (those within 3 robust sigmas of the median, which the local values
  /// average), each scaled by its sensitivity to its three transitions' offsets [px]; 0 with
  /// fewer than 2. For edge_bias_covariance().
  std::array<double, 2> edge_offset_sd{};
  /// Transitions of the data cells are numbered X axis first: those from this one on are Y's.
  int first_y_transition = 0;
  /// Per side: the thickness error a correct quad has, discounted before the limit: where both
  /// axes' biases were measured (and every side the bitmap lets us measure), the part of
  /// thickness_error that 2 b (1 - 1/n) explains, b the local bias across the side at each
  /// inner-edge point; otherwise common_offset.
  std::array<double, 4> expected_thickness_error{};
  /// Per side: the standard error of the thickness error, from the scatter of the inner-edge
  /// offsets about the line fitted along the side, one independent measurement per data cell
  /// (the five points of a cell share its print), at the end of the measured stretch further
  /// from the points' centre (the larger of the two ends'). NaN where the thickness error is.
  std::array<double, 4> thickness_se{};
  /// The deviation every measured side shares, as a fraction of the cell across each side,
  /// taken off each (that fraction of its own cell) before the limit
  /// (DetectorSettings::border_shared_deviation) [cells]; 0 where the sides disagree in sign.
  double shared_deviation = 0.0;
  /// Per side, a quarter and three quarters along it: the print's edge bias across the side
  /// there (the local value of edge_bias of the axis across it, clamped as the test does)
  /// [px]; NaN where the bias was not measured on both axes. remove_edge_bias() uses it.
  std::array<std::array<double, 2>, 4> side_edge_bias{
      {{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()},
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()},
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()},
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()}}};
  /// Per side end (as side_edge_bias): the derivative of its value (a weighted mean of its
  /// axis's estimates, each linear in three transitions' offsets) with respect to those offsets,
  /// as (transition, coefficient) pairs; empty where the corners are not moved by it (the
  /// deadband, not measured, clamped). edge_bias_covariance() uses them.
  std::array<std::array<std::vector<std::pair<int, double>>, 2>, 4> side_edge_bias_sensitivity;
  /// The sides' bow and where it puts the corners (quad_bow()); measured where the other tests
  /// passed and DetectorSettings::border_max_bow > 0.
  QuadBow bow;
  /// The check passed and the bow is to be taken off the corners (take_off_bow();
  /// DetectorSettings::border_bow_correction, border_bow_min_cell).
  bool bow_taken_off = false;
  /// Where the quad was considered as a bent print (DetectorSettings::border_max_bent): how far
  /// the border's inner edge bows with its outer edge, 1 as a bent print's does, 0 where it is
  /// straight (an occluder's outline bows the outer edge alone), the sides' estimates combined
  /// by their precision, and its standard error. NaN where not measured.
  double inner_bow = std::numeric_limits<double>::quiet_NaN();
  double inner_bow_se = std::numeric_limits<double>::quiet_NaN();
  /// Kept as a bent print: the quad failed with its straight sides, its inner edge bows with
  /// the outer one (inner_bow above 0.5, standard error at most 0.5), and it passed with the
  /// border sampled along its bowed sides (DetectorSettings::border_max_bent); bow_taken_off too.
  bool bent = false;
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
///    magnitude). What a correct side's e_k is depends on how the print is imaged: every
///    black/white edge of it appears displaced toward the white by a bias b (ink spread and
///    bloom: b > 0; a camera's tone curve on a blurred print: b < 0, about 0.42 sigma per edge;
///    motion blur: along its direction only, so b is measured per tag axis). The sides are
///    fitted to the outer edges, so the quad is the true one dilated by b and the cell it
///    predicts 2 b / n too large, while the inner edge lies b further in: a correct side's
///    inner-edge offsets are 2 b (1 - 1/n). The print's model (DetectorSettings::
///    border_edge_bias) measures b on the tag's own data cells, independently of where the
///    sides are: along every data row and column the interior black/white transitions are
///    located (edge_offset), consecutive transitions bound runs of k cells whose measured
///    length differs from the mapped one by d = 2 b p + k eps (p = +1 for a black run, -1 for a
///    white one, eps the homography's local scale error per cell), and each pair of adjacent
///    runs gives b = (d1/k1 - d2/k2) / (2 p1 (1/k1 + 1/k2)) with eps eliminated. Per axis
///    (sides 0 and 2 use the Y axis's estimates, 1 and 3 the X axis's), after leaving out those
///    further than 3 robust sigmas from the median (`edge_bias`), the local bias at each
///    inner-edge point is their mean weighted by a Gaussian of 1.5 cells in distance on the tag
///    (perspective grows the cells, and an ink spread in pixels with them, toward the near
///    side), clamped to border_max_edge_bias cells; 2 b (1 - 1/n) is taken off each offset
///    before the line fit, and the side fails when the resulting |e_k| exceeds
///    border_max_thickness_error (needs 4 points), 0.5 px
///    more in a point-sampled image (`aliased`). A side fitted to an occluder's outline, or
///    moved off the border, adds its own error, which the other sides and the cells do not
///    share. Where b is not measured on both axes (fewer than 4 pairs, or the model off) or a
///    side the bitmap lets us measure was not measured, the
///    shared-thinning discount applies instead: when at least 3 sides are measured, every side
///    with a white data cell next to it among them, and all are thinner (e_k < 0), the common
///    offset c is the error of the least thin one, but no lower than -border_blur_allowance x
///    `edge_blur`, otherwise c = 0, and the side fails when |e_k - c| exceeds the limit.
/// Where all sides pass, their straightness (DetectorSettings::border_max_bow): the check fails
/// where the sides' outer edges bow so that a corner lies more than border_max_bow px from
/// where they end (quad_bow(); a bent card or distortion the calibration leaves: the quad's
/// corners are then not the print's).
/// Where the check fails, a bent print (DetectorSettings::border_max_bent): where the sides' bow
/// is one a flat tag does not show and the border's inner edge bows with the outer one
/// (`inner_bow`), the check runs again on the quad whose corners are where the bowed sides end,
/// every border sample moved as the bowed outer edge lies off that quad's side; where it passes,
/// that result with `bent` and `bow_taken_off` set.
/// Families without a black border ring inside a white one (tagStandard41h12, ...) are not
/// checked (`checked` false).
/// `edges`: the edge-line fit's samples of these corners (refine_corners()), for the
/// straight-sides test (else it samples the sides itself).
BorderCheck check_border(const cv::Mat& gray, const std::array<cv::Point2d, 4>& corners,
                         const cv::Mat& pattern, int border_cells, const DetectorSettings& s,
                         const io::Calibration* calib = nullptr,
                         const EdgeSamples* edges = nullptr);

/// The corners of the print's cell grid from corners fitted to the outer edges of its black
/// border: every black/white edge of a print is imaged displaced toward the white by the edge
/// bias b (ink spread, bloom: b > 0; a camera's tone curve on a blurred print: b < 0; motion
/// blur: along its axis), so the fitted quad is the grid's dilated by b. Each side is moved
/// inward by the bias across it (BorderCheck::side_edge_bias, measured on the tag's own data
/// cells, a quarter and three quarters along the side: perspective grows it toward the near
/// side), in undistorted pixels where `calib` has distortion, and the corners are the moved
/// sides' intersections. The corners unchanged where the bias was not measured.
std::array<cv::Point2d, 4> remove_edge_bias(const std::array<cv::Point2d, 4>& corners,
                                            const BorderCheck& check,
                                            const io::Calibration* calib = nullptr);

/// The corners with the one side that failed check_border() on its thickness alone moved toward
/// its border's inner edge: by `fraction` of the way to one cell (as the moved quad maps it)
/// outside the inner edge the check measured next to the white data cells, after the print's
/// model (the residual thickness_error - expected_thickness_error, r; moving a side out by x
/// grows the cell across it by x / n, so the side moves by fraction x r n / (n - 1)), in
/// undistorted pixels where `calib` has distortion. Empty unless exactly one side failed, and on
/// thickness alone, every other measured side's residual is at most half of that side's (where
/// several sides deviate, which one is off is not determined: a quad realigned on the wrong one
/// can pass the check as well), no side failed its contrast test or has quiet-zone samples
/// outside the image, and the residual is at most DetectorSettings::border_max_edge_bias of the
/// side's cell.
std::optional<std::array<cv::Point2d, 4>> realign_sides(const std::array<cv::Point2d, 4>& corners,
                                                        const BorderCheck& check, int border_cells,
                                                        const DetectorSettings& s,
                                                        double fraction = 1.0,
                                                        const io::Calibration* calib = nullptr);

/// A quad's corners undecided between `a` and `b` (realign_sides() at fraction 0 and 1): the
/// covariance of taking their midpoint when either is the truth with equal weight, v v^T with v
/// the stacked half differences (b - a) / 2 [px^2]: the sides' two explanations move both
/// corners of a side together.
CornerCovariance undecided_covariance(const std::array<cv::Point2d, 4>& a,
                                      const std::array<cv::Point2d, 4>& b);

/// A quad kept by realign_and_check().
struct Realigned {
  /// The side that failed on its thickness alone halfway between its outer edge and one cell
  /// outside its inner edge (realign_sides() at 0.5).
  std::array<cv::Point2d, 4> corners;
  std::array<cv::Point2d, 4> inner;  ///< that side on its inner edge (realign_sides() at 1)
  BorderCheck check;                 ///< check_border() of `inner`: passed
  CornerCovariance covariance;       ///< undecided_covariance() of the fitted and `inner` corners
};

/// A side off its border's inner edge, undecided (DetectorSettings::border_realign_max). Where
/// `check` (check_border() of `corners`) failed on the thickness of one side alone
/// (realign_sides()), that side is moved onto its inner edge and the check is run on that quad
/// again, with border_shared_deviation off (it could take the moved side's error off the
/// others); where it passes and no corner moved by more than border_realign_max, the quad with
/// the side halfway. Either the side was off the print (an occluder's outline, a wrong quad: the
/// inner edge is right) or the print's border is thinner or thicker there (the outer edge is
/// right); halfway, a corner is off by at most half its movement either way. Empty otherwise,
/// or with border_realign_max 0.
std::optional<Realigned> realign_and_check(const cv::Mat& gray,
                                           const std::array<cv::Point2d, 4>& corners,
                                           const BorderCheck& check, const cv::Mat& pattern,
                                           int border_cells, const DetectorSettings& s,
                                           const io::Calibration* calib = nullptr);

/// The covariance remove_edge_bias() adds to the corners [px^2, undistorted pixels where `calib`
/// has distortion, as refine_corners()], to first order: each side end's value is linear in
/// the measured offsets of the data cells' transitions (side_edge_bias_sensitivity), which are
/// independent with their axis's edge_offset_sd (neighbouring estimates share transitions, so
/// they are not independent), so transition t moves the corners by the sum over the side ends
/// of its coefficient there times J_end, the corners' derivative with respect to that end's
/// value (finite differences of remove_edge_bias). Zero where the correction left the corners.
CornerCovariance edge_bias_covariance(const std::array<cv::Point2d, 4>& corners,
                                      const BorderCheck& check, const io::Calibration* calib);

/// The corners moved to where the bowed sides end: each by bow.corner_shift (quad_bow()), in
/// undistorted pixels where `calib` has distortion. Unchanged where the bow was not measured.
std::array<cv::Point2d, 4> take_off_bow(const std::array<cv::Point2d, 4>& corners,
                                        const QuadBow& bow, const io::Calibration* calib = nullptr);

/// The covariance take_off_bow() adds to the corners [px^2, undistorted pixels where the
/// calibration has distortion, as refine_corners()]: each corner's shift with its standard error
/// along it (QuadBow::corner_se; the shifts' correlation between corners is left out).
CornerCovariance bow_covariance(const QuadBow& bow);

}  // namespace netvmo::frontend
