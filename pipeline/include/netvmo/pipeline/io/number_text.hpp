// Numbers read from text files and options: one rule for what a number is, so that every reader
// (CSV, TUM, node journals, option lists) accepts and refuses the same tokens. Each caller words
// its own error, naming its file, line and field.
#pragma once

#include <optional>
#include <string>

namespace netvmo::io {

/// The number `token` spells when the whole token is one (strtod's syntax: leading white space,
/// a sign, decimal or exponent form) and finite; nullopt otherwise (empty, trailing characters,
/// nan, inf, 1e999). A number below double's smallest is read as strtod rounds it (a subnormal
/// number, or 0), so that everything io::exact_text writes reads back as itself.
std::optional<double> parse_finite(const std::string& token);

/// The integer `token` spells: parse_finite's number, integral ("3", "3.0", "1e2") and within
/// int's range; nullopt otherwise.
std::optional<int> parse_int(const std::string& token);

}  // namespace netvmo::io
