// Small helpers shared by the `cairn slam` verbs: strict number parsing for options and a flat JSON object
// writer (numbers with round-trip precision, strings escaped).
#pragma once

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "cairn/strict_number.hpp"

namespace cairn::slam_cli {

inline std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

inline std::string jsonString(const std::string& s) {
  std::string out(1, '"');
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  out.push_back('"');
  return out;
}

/// Builds `{"k":v,...}` in insertion order.
class JsonObject {
 public:
  JsonObject& raw(const std::string& key, const std::string& json) {
    if (!body_.empty()) body_.push_back(',');
    body_.append(jsonString(key));
    body_.push_back(':');
    body_.append(json);
    return *this;
  }
  JsonObject& num(const std::string& key, double v) { return raw(key, jsonNumber(v)); }
  JsonObject& integer(const std::string& key, long long v) { return raw(key, std::to_string(v)); }
  JsonObject& str(const std::string& key, const std::string& v) { return raw(key, jsonString(v)); }
  std::string text() const {
    std::string out(1, '{');
    out.append(body_);
    out.push_back('}');
    return out;
  }

 private:
  std::string body_;
};

/// Whole-string integer that fits an int; throws std::invalid_argument "<what> must be an integer, got '<s>'".
inline int parseInt(const std::string& s, const char* what) {
  const auto v = strict_number::parse_integer(s);
  if (!v || *v < std::numeric_limits<int>::min() || *v > std::numeric_limits<int>::max())
    throw std::invalid_argument(std::string(what) + " must be an integer, got '" + s + "'");
  return static_cast<int>(*v);
}

/// Whole-string finite number; throws std::invalid_argument like parseInt.
inline double parseDouble(const std::string& s, const char* what) {
  const auto v = strict_number::parse_finite(s);
  if (!v) throw std::invalid_argument(std::string(what) + " must be a number, got '" + s + "'");
  return *v;
}

}  // namespace cairn::slam_cli
