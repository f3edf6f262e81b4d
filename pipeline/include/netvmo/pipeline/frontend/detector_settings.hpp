// The front end's detector settings: libapriltag's, the target decision's, the refinement's and
// the border check's, as one plain struct with documented defaults.
#pragma once

#include <string>
#include <vector>

#include "netvmo/pipeline/frontend/refine.hpp"

namespace netvmo::frontend {

/// Detector settings. Defaults documented next to each field.
struct DetectorSettings {
  // libapriltag (apriltag_detector_t) settings
  std::string family = "tag36h11";  ///< tag family (see render::tag_families())
  double quad_decimate = 2.0;       ///< decimation of the image for quad search (>= 1)
  double quad_sigma = 0.0;          ///< Gaussian blur sigma applied before quad search
  /// Worker threads of libapriltag. 1: the detection runs on the calling thread. libapriltag
  /// 3.3.0 (Debian 12) has a race in its worker pool: a worker woken spuriously may read a task
  /// from an array that workerpool_add_task is reallocating, and call through a stale pointer
  /// (AprilRobotics/apriltag pull request 339, merged after 3.3.0). Seen once here as a SEGV in
  /// a libapriltag thread under AddressSanitizer. netvmo runs cameras in parallel itself (one
  /// detector per worker, ImageRunSettings::workers), so 1 costs `netvmo run` nothing; > 1 only
  /// speeds up a single camera's detection, with that risk.
  int nthreads = 1;
  bool refine_edges = true;         ///< libapriltag's edge refinement of the quads
  double decode_sharpening = 0.25;  ///< sharpening of the decoded bit samples
  int bits_corrected = 2;           ///< error bits the decoder may correct (libapriltag default)
  /// libapriltag qtp.min_white_black_diff: local contrast (gray levels) below which a region is
  /// not thresholded. libapriltag's default is 5; 20 skips the quad fitting of sensor-noise
  /// clusters (about 5x faster on 640x480 frames with noise sigma 2, see docs/benchmarks.md,
  /// "Front end") and still finds tags whose black/white contrast is 40 gray levels or more
  /// (tested).
  int min_white_black_diff = 20;
  // Acceptance of the target tag
  int target_id = 0;  ///< the target's (primary) tag id
  /// The ids of the body's other tags (a tag bundle: network.yaml's target.bundle, in its
  /// order), each decided by the same rules as target_id. Empty (default): a single tag.
  std::vector<int> bundle_ids;
  /// Several targets (network.yaml `targets:`), decided in the same pass: how many of the tags
  /// [target_id, bundle_ids...] belong to each target, in order (target j's tags follow target
  /// j - 1's; each target is decided as a body of its own). Empty (default): one target.
  std::vector<int> tags_per_target;
  double min_decision_margin = 20.0;  ///< reject target detections with a lower decision margin
  int max_hamming = 1;                ///< reject target detections with more corrected bits
  // Refinement of the accepted target's corners
  Refinement refinement = Refinement::edge_lines;
  /// The corners' standard deviation [px] where the refinement gives no covariance of its own
  /// (none, subpix, or an edge fit refused): a stated prior for the measurement's covariance
  /// (Observation::f_covariance), each coordinate independent. 0.3 px is about what
  /// libapriltag's own edge refinement reaches on sharp, well-lit tags; the edge fits' covariance
  /// replaces it wherever they are used (the default).
  double corner_sigma_px = 0.3;
  // Border / quiet-zone consistency check of the accepted target's refined corners (see
  // check_border()): a quad with a side on an occluder's outline, a shadow edge or the image
  // border is rejected as TargetStatus::border_mismatch.
  bool border_check = true;
  /// A contrast sample passes when (quiet zone - border) >= this x (local white - border).
  /// 0.2 keeps a quiet zone in deep shadow next to a lit border (0.3 of the lit white, as the
  /// renderer's ambient-only shadows); an occluder close to the black ink fails it.
  double border_min_contrast = 0.2;
  /// A side fails when more than this fraction of its contrast samples fail.
  double border_max_failed_fraction = 0.2;
  /// A side fails when the inner edge of its black border (measured where the adjacent data
  /// cell is white) lies further than this from one cell inside the side [px]. Measured on
  /// rendered frames: at most 0.49 px on fully visible tags, at least 0.68 px on quads with
  /// a corner more than 1 px off (docs/frontend.md, "What the table shows").
  double border_max_thickness_error = 0.6;
  /// Blur allowance of the thickness test [px of offset per px of measured blur]: when every
  /// measured side (at least 3, and every side with a white data cell next to it) looks thinner
  /// than a cell, the thinning of the least thin one is discounted from all sides, up to this x
  /// BorderCheck::edge_blur. 1.0 covers a gamma-encoded camera: encoding (v^(1/2.2)) an edge
  /// blurred by a Gaussian of sigma s moves it 0.42 s (black ink at 5 % of the white) to 0.47 s
  /// (3 %) toward the dark side, so a correct border looks 0.83-0.94 s thinner on all sides.
  /// 0: the fixed limit alone.
  double border_blur_allowance = 1.0;
  /// Measure the print's edge bias on the tag's own cells (BorderCheck::edge_bias) and hold
  /// each side's thickness error to the limit around the error a correct quad then has,
  /// 2 b (1 - 1/n), instead of around 0 (ink spread, the tone curve under blur and motion blur
  /// move every edge of the print alike; a side off the border moves alone). Where the bias
  /// cannot be measured on both axes (fewer than 4 pairs of runs), the shared-thinning
  /// discount (border_blur_allowance) applies. false: that discount alone.
  bool border_edge_bias = true;
  /// The largest edge bias believed [cells] (ink spread beyond a quarter cell would merge the
  /// cells of the code); a larger measured bias is clamped to it.
  double border_max_edge_bias = 0.25;
  /// With the print's model: a side's limit is at least this x the scatter of the edge-bias
  /// estimates across it (BorderCheck::edge_bias_scatter), the irregularity of this print's
  /// edges as imaged, which its border shares (0.03 px on clean renderings, 0.04-0.3 px on real
  /// photos). 0: the fixed limit alone.
  double border_scatter_allowance = 4.0;
  /// A real print's border is not exactly one of its cells thick, but it is the same on all four
  /// sides: where at least three sides are measured and all deviate the same way after the
  /// print's edge bias, the least deviating one's deviation (at most border_max_edge_bias of a
  /// cell) is taken off every side (BorderCheck::shared_deviation). A side on an occluder's
  /// outline deviates alone. false: off.
  bool border_shared_deviation = true;
  /// A side's thickness error fails only when it also exceeds this many of its own standard
  /// errors (BorderCheck::thickness_se: the scatter of the inner-edge offsets along the side,
  /// one independent measurement per data cell): a deviation within a noisy image's own
  /// measurement noise is no evidence of a wrong side. 0: off.
  double border_significance = 3.0;
  /// Straight sides: a flat print imaged by a pinhole camera (distortion removed) has straight
  /// sides. Where a quadratic fitted to a side's outer edge samples ends away from the straight
  /// line fitted to them (a bent card, distortion the calibration leaves), the straight sides
  /// meet away from the print's corner. The check fails when that puts a corner more than this
  /// far from where the bowed edges end [px] and by more than border_significance of its
  /// standard error (BorderCheck::bow, quad_bow()). 0: off.
  double border_max_bow = 1.0;
  /// Bowed sides taken off: where the check passes and the sides' bow puts some corner more than
  /// this far from where the straight sides meet [px] (and by more than border_significance of
  /// its standard error), every corner is moved by its QuadBow::corner_shift, to where the bowed
  /// edges end (BorderCheck::bow_taken_off). 0.7 px is border_max_bow less the shift's own error
  /// on bent cards (at most 0.30 px), so that a corner left where the straight sides meet is
  /// within 1 px of the print's; flat tags whose cells are at least 3 px show at most 0.48 px of
  /// bow, also sharpened (docs/frontend.md, "Bent prints: straight sides").
  /// Not in a point-sampled image (its staircase bends the sides). 0: off.
  double border_bow_correction = 0.7;
  /// The narrowest cell [px] (the quad's shortest side over the black square's cells) on which
  /// the bow is taken off: on small cells a camera's sharpening or tone curve, which the blur
  /// estimate reads as no blur, lets the data cells next to the border move the outer edge's
  /// samples, and flat tags look bowed: up to 0.9 px on cells under 2 px (sharpened,
  /// BorderCheck.SharpenedSmallCellsLookBowed), 0.5-0.7 px on cells of 2.5 px (rendered in
  /// sRGB), at most 0.48 px from 3 px; 4 px keeps a cell's margin above those.
  double border_bow_min_cell = 4.0;
  /// A bent print [px of a corner's shift; 0: off]. A print bent in the hand or curling off a
  /// wall, or imaged through lens distortion the calibration leaves, bows its sides, and its
  /// border's inner edge bows with the outer one: against the straight sides its border looks
  /// thinner or thicker, or the straight sides miss its corners by more than border_max_bow.
  /// Where the check fails, the sides' bow is one a flat tag would not show (as for
  /// border_bow_correction, on cells of at least border_bow_min_cell) and no corner's shift
  /// exceeds this, and the border's inner edge bows with the outer one (BorderCheck::inner_bow:
  /// an occluder's outline bows the outer edge alone), the check runs again on the quad whose
  /// corners are where the bowed sides end, every border sample moved as its side's outer edge
  /// is bowed there; where that passes, the quad is kept with the bow taken off
  /// (BorderCheck::bent). 4 px: up to there the shift puts the corners within 0.3-0.5 px of where
  /// the bowed sides end (the bent side's image is a conic, the fit a parabola;
  /// BorderCheck.QuadBowPutsTheCornersWhereTheBentSidesEnd).
  double border_max_bent = 4.0;
  /// A side off its border's inner edge, undecided [px of corner movement; 0: off]. Where the
  /// check fails on the thickness of one side alone (every side's contrast passes, every other
  /// side deviates by at most half as much), either that side is off the print (an occluder's
  /// outline, a wrong quad: the inner edge is right) or the print's border is thinner or thicker
  /// there (a trimmed or misregistered print: the outer edge is right); one picture cannot tell
  /// them apart. The side is moved onto its inner edge (one cell outside it, realign_sides())
  /// and the check run again on that quad: where it passes and no corner moves by more than
  /// this, the tag is kept with the side halfway between the two, so a corner is off by at most
  /// half its movement whichever is true, and the two explanations' spread is added to the
  /// corners' covariance. 1 px keeps a corner within 0.5 px of either (docs/frontend.md, "A side
  /// between two edges"; at 1.5 px halfway corners reached 1.5 px from the truth on synthesized
  /// pictures whose fitted quad was itself pulled by a dark surround).
  double border_realign_max = 1.0;
  /// Report the corners of the print's cell grid (remove_edge_bias()): each side of the quad
  /// fitted to the black border's outer edges moved inward by the print's edge bias the check
  /// measured across it on the tag's own data cells (ink spread and bloom grow the black, a
  /// camera's tone curve on a blurred print shrinks it; both would otherwise scale the tag and
  /// move PnP's distance by 2 b / side). network.yaml's tag size is then the bitmap's n cells as
  /// generated. Needs the border check and the print's model (border_edge_bias); where the bias
  /// was not measured the corners stay as fitted. false: the fitted corners.
  bool correct_edge_bias = true;
  /// The edge bias below which an axis's corners are not corrected [px]: what the estimator
  /// measures on clean renderings, whose prints and imaging have no bias (|b| <= 0.13 px on
  /// paper5_render and occluder_sweep, 2026-12-02; docs/frontend.md). Correcting by that much
  /// would move the corners by the estimator's own error.
  double edge_bias_deadband = 0.15;
};

/// Throws InputError naming the first field out of its range.
void validate(const DetectorSettings& s);

}  // namespace netvmo::frontend
