#include "netvmo/pipeline/frontend/decision.hpp"

#include <algorithm>
#include <cstdio>

#include "netvmo/pipeline/error.hpp"

namespace netvmo::frontend {

TagDecision decide_tag(int tag_id, std::vector<TagDetection>& all, const DetectorSettings& s,
                       const CandidateChecker& check) {
  char buf[200];
  TagDecision dec;
  dec.id = tag_id;
  int n_id = 0, n_hamming_ok = 0, n_margin_ok = 0, n_passed = 0, passed = -1;
  double best_margin = -1.0;
  int best_hamming = 1 << 30;
  std::string border_reason;
  for (size_t i = 0; i < all.size(); ++i) {
    TagDetection& d = all[i];
    if (d.id != tag_id) continue;
    ++n_id;
    best_hamming = std::min(best_hamming, d.hamming);
    if (d.hamming > s.max_hamming) continue;
    ++n_hamming_ok;
    best_margin = std::max(best_margin, d.margin);
    if (d.margin < s.min_decision_margin) continue;
    ++n_margin_ok;
    std::array<cv::Point2d, 4> corners = d.corners;
    const CandidateCheck bc = check(corners);
    if (!bc.ok) {
      if (border_reason.empty()) border_reason = bc.reason;
      continue;
    }
    d.corners = corners;  // only a passing candidate's corners are replaced by refined ones
    d.corner_covariance = bc.corner_covariance;
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
    std::snprintf(buf, sizeof buf, "%d corrected bits, more than %d", best_hamming, s.max_hamming);
  } else {
    std::snprintf(buf, sizeof buf, "id %d not decoded (%zu other tag(s) decoded)", tag_id,
                  all.size());
  }
  dec.reason = buf;
  return dec;
}

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

}  // namespace netvmo::frontend
