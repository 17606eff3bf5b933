#include "cairn/bt_executive/value.hpp"

#include <cxxabi.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "cairn/bt_executive/status.hpp"

namespace cairn::bt {

std::optional<NodeStatus> statusFromString(std::string_view s) {
  for (auto st : {NodeStatus::IDLE, NodeStatus::RUNNING, NodeStatus::SUCCESS, NodeStatus::FAILURE,
                  NodeStatus::SKIPPED})
    if (toString(st) == s) return st;
  return std::nullopt;
}

std::string_view valueTypeName(const Value& v) {
  switch (v.index()) {
    case 0: return "unset";
    case 1: return "bool";
    case 2: return "int";
    case 3: return "double";
    default: return "string";
  }
}

std::string valueToString(const Value& v) {
  switch (v.index()) {
    case 0: return "";
    case 1: return std::get<bool>(v) ? "true" : "false";
    case 2: return std::to_string(std::get<std::int64_t>(v));
    case 3: {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.17g", std::get<double>(v));
      // shortest representation that round-trips
      for (int prec = 1; prec <= 17; ++prec) {
        char b2[64];
        std::snprintf(b2, sizeof b2, "%.*g", prec, std::get<double>(v));
        if (std::strtod(b2, nullptr) == std::get<double>(v)) return b2;
      }
      return buf;
    }
    default: return std::get<std::string>(v);
  }
}

Value parseLiteral(std::string_view s) {
  if (!s.empty()) {
    std::int64_t i{};
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
    if (ec == std::errc() && p == s.data() + s.size()) return Value(i);
    double d{};
    auto [p2, ec2] = std::from_chars(s.data(), s.data() + s.size(), d);
    if (ec2 == std::errc() && p2 == s.data() + s.size()) return Value(d);
  }
  if (s == "true") return Value(true);
  if (s == "false") return Value(false);
  return Value(std::string(s));
}

std::string demangle(const char* mangled) {
  int status = 0;
  std::unique_ptr<char, void (*)(void*)> p(abi::__cxa_demangle(mangled, nullptr, nullptr, &status), std::free);
  return status == 0 && p ? std::string(p.get()) : std::string(mangled);
}

}  // namespace cairn::bt
