#include "netvmo/pipeline/io/number_text.hpp"

#include <climits>
#include <cmath>
#include <cstdlib>

namespace netvmo::io {

std::optional<double> parse_finite(const std::string& token) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  // Overflow is +-HUGE_VAL, not finite. Underflow (strtod's ERANGE too) is kept: a subnormal
  // number, as io::exact_text writes one, reads back as itself, and a smaller one as 0.
  if (token.empty() || end == token.c_str() || *end != '\0' || !std::isfinite(v))
    return std::nullopt;
  return v;
}

std::optional<int> parse_int(const std::string& token) {
  const auto v = parse_finite(token);
  // Range first: converting a double outside int's range is undefined behaviour.
  if (!v || !(*v >= INT_MIN && *v <= INT_MAX) || *v != std::floor(*v)) return std::nullopt;
  return static_cast<int>(*v);
}

}  // namespace netvmo::io
