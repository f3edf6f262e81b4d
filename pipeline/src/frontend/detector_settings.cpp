#include "netvmo/pipeline/frontend/detector_settings.hpp"

#include <algorithm>
#include <cmath>

#include "netvmo/pipeline/error.hpp"
#include "netvmo/render/tag_family.hpp"

namespace netvmo::frontend {

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
  if (!(s.border_max_edge_bias >= 0.0 && s.border_max_edge_bias <= 0.5))
    bad("border_max_edge_bias must be in 0..0.5 (cells)");
  if (!(s.border_scatter_allowance >= 0.0 && s.border_scatter_allowance <= 20.0))
    bad("border_scatter_allowance must be in 0..20");
  if (!(s.border_significance >= 0.0 && s.border_significance <= 20.0))
    bad("border_significance must be in 0..20");
  if (!(s.border_max_bow >= 0.0 && s.border_max_bow <= 100.0))
    bad("border_max_bow must be in 0..100 (px; 0: off)");
  if (!(s.border_bow_correction >= 0.0 && s.border_bow_correction <= 100.0))
    bad("border_bow_correction must be in 0..100 (px; 0: off)");
  if (!(s.border_realign_max >= 0.0 && s.border_realign_max <= 100.0))
    bad("border_realign_max must be in 0..100 (px; 0: off)");
  if (!(s.border_bow_min_cell >= 0.0 && s.border_bow_min_cell <= 1000.0))
    bad("border_bow_min_cell must be in 0..1000 (px)");
  if (!(s.border_max_bent >= 0.0 && s.border_max_bent <= 100.0))
    bad("border_max_bent must be in 0..100 (px; 0: off)");
  if (!(s.edge_bias_deadband >= 0.0)) bad("edge_bias_deadband must be >= 0");
  if (!(s.corner_sigma_px > 0.0 && std::isfinite(s.corner_sigma_px)))
    bad("corner_sigma_px must be > 0 and finite");
}

}  // namespace netvmo::frontend
