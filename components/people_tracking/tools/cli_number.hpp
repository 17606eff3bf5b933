// One parser for the numeric command-line options of the `cairn people` verbs.
#pragma once

#include <cmath>
#include <cstdlib>
#include <string>

#include "cairn/people_tracking/scan.hpp"  // InputError

namespace cairn::people_tracking {

// The value of `option` as a finite number; InputError ("option --x expects a (finite) number, got '…'") otherwise.
inline double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') throw InputError("option " + option + " expects a number, got '" + text + "'");
  if (!std::isfinite(x)) throw InputError("option " + option + " expects a finite number, got '" + text + "'");
  return x;
}

}  // namespace cairn::people_tracking
