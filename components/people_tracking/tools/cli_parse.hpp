// Parsers shared by the `cairn people` verbs' command-line options: numbers and comma-separated lists.
#pragma once

#include <climits>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/people_tracking/param_ranges.hpp"
#include "cairn/people_tracking/scan.hpp"  // InputError
#include "cairn/strict_number.hpp"

namespace cairn::people_tracking {

// Seeds: any non-negative 64-bit signed integer.
inline constexpr long long kMaxSeed = LLONG_MAX;

// The value of `option` as a finite number; InputError ("option --x expects a (finite) number, got '…'") otherwise.
inline double parseNumber(const std::string& option, const std::string& text) {
  const auto x = strict_number::parse_finite(text);
  if (!x) throw InputError("option " + option + " expects a finite number, got '" + text + "'");
  return *x;
}

// The value of `option` as an integer in [lo, hi]; InputError ("option --x expects an integer in [lo, hi], got
// '…'") otherwise: no fractions ("2.5"), trailing text, or values out of range (also none that overflow).
inline long long parseInteger(const std::string& option, const std::string& text, long long lo, long long hi) {
  const auto x = strict_number::parse_integer(text);
  if (!x || *x < lo || *x > hi)
    throw InputError("option " + option + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got '" + text + "'");
  return *x;
}

// The value of `option`, which sets the core parameter `param` (param_ranges.hpp, the component's ranges), as a
// number inside that parameter's range.
inline double parseParam(const std::string& option, const std::string& text, std::string_view param) {
  const double x = parseNumber(option, text);
  const ParamRange r = paramRange(param);
  if (!(x >= r.lo && x <= r.hi))
    throw InputError("option " + option + " expects a number in " + rangeText(r) + ", got '" + text + "'");
  return x;
}

// The same for an integer parameter.
inline long long parseIntegerParam(const std::string& option, const std::string& text, std::string_view param) {
  const ParamRange r = paramRange(param);
  return parseInteger(option, text, std::llround(r.lo), std::llround(r.hi));
}

// "a,b,c" -> {"a", "b", "c"}; every field is kept, empty ones too ("" -> {""}, "a," -> {"a", ""}).
inline std::vector<std::string> splitCommas(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t begin = 0;;) {
    const std::size_t end = text.find(',', begin);
    out.push_back(text.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
    if (end == std::string::npos) return out;
    begin = end + 1;
  }
}

}  // namespace cairn::people_tracking
