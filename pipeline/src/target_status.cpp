#include "netvmo/pipeline/target_status.hpp"

#include "netvmo/pipeline/error.hpp"

namespace netvmo::frontend {

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

}  // namespace netvmo::frontend
