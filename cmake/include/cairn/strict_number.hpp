// One implementation of "is this text a number" for every cairn package: command-line options, YAML scalars,
// parameter and QoS strings. The whole text must be the number: decimal (std::from_chars, so the locale does not
// matter), an optional leading '+' (YAML and strtod accept it), no spaces, nothing after it. Each caller keeps
// its own error message (tools name the option, file readers file:line), and its own range.
//
// It lives under cmake/ because every package includes cmake/CairnCommon.cmake by relative path (colcon builds
// packages one by one): `cairn_use_strict_number(target)` puts this directory on a target's private include path.
// Build tree only: it is never installed and no public header includes it.
#pragma once

#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>
#include <system_error>

namespace cairn::strict_number {

namespace detail {
// The text after an optional leading '+', or nullopt when a sign follows it ("+-3", "++3").
inline std::optional<std::string_view> unsigned_plus(std::string_view text) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '-' || text.front() == '+')) return std::nullopt;
  }
  return text;
}
}  // namespace detail

// A finite number ("3", "-0.5", "1e-3", "+2"); nullopt for "", " 3", "3 ", "0x10", "inf", "nan", "3m", and for
// values a double cannot hold ("1e400").
inline std::optional<double> parse_finite(std::string_view text) {
  const auto t = detail::unsigned_plus(text);
  if (!t || t->empty()) return std::nullopt;
  double x = 0;
  const auto [end, ec] = std::from_chars(t->data(), t->data() + t->size(), x);
  if (ec != std::errc() || end != t->data() + t->size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

// A whole number that fits a long long ("42", "-7", "+3"); nullopt for "2.5", "1e3", "", "0x10", overflow.
inline std::optional<long long> parse_integer(std::string_view text) {
  const auto t = detail::unsigned_plus(text);
  if (!t || t->empty()) return std::nullopt;
  long long x = 0;
  const auto [end, ec] = std::from_chars(t->data(), t->data() + t->size(), x);
  if (ec != std::errc() || end != t->data() + t->size()) return std::nullopt;
  return x;
}

}  // namespace cairn::strict_number
