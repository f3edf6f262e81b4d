// Numbers read from text files and options: one rule for what a number is, so that every reader
// (CSV, TUM, node journals, option lists) accepts and refuses the same tokens. Each caller words
// its own error, naming its file, line and field.
#pragma once

#include <optional>
#include <string>

namespace netvmo::io {

/// The number `token` spells when the whole token is one (strtod's syntax: leading white space,
/// a sign, decimal or exponent form), finite and within double's range (no overflow or
/// underflow); nullopt otherwise (empty, trailing characters, nan, inf, 1e999, 1e-999).
std::optional<double> parse_finite(const std::string& token);

/// The integer `token` spells: parse_finite's number, integral ("3", "3.0", "1e2") and within
/// int's range; nullopt otherwise.
std::optional<int> parse_int(const std::string& token);

}  // namespace netvmo::io
