// Dynamic values used by the script language and by untyped blackboard entries, plus string -> T conversion
// used to convert port literals at load time.
#pragma once

#include <charconv>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeindex>
#include <variant>

namespace cairn::bt {

/// A script value. `std::monostate` means "no value" (an entry that was never written).
using Value = std::variant<std::monostate, bool, std::int64_t, double, std::string>;

std::string_view valueTypeName(const Value& v);
std::string valueToString(const Value& v);
/// Interprets a literal the way SetBlackboard / SubTree literals into untyped entries do:
/// integer, then floating point, then true/false, else the string itself.
Value parseLiteral(std::string_view s);

/// Thrown when a string cannot be converted to a port's type.
struct ConversionError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// String conversion trait. Specialize `Convert<T>` (with `static T fromString(std::string_view)`) to make a
/// user type usable as a literal port value in XML; types without it can only be bound to blackboard entries.
template <class T, class Enable = void>
struct Convert {
  static constexpr bool available = false;
};

template <>
struct Convert<std::string> {
  static constexpr bool available = true;
  static std::string fromString(std::string_view s) { return std::string(s); }
};

template <>
struct Convert<bool> {
  static constexpr bool available = true;
  static bool fromString(std::string_view s) {
    if (s == "true" || s == "True" || s == "TRUE" || s == "1") return true;
    if (s == "false" || s == "False" || s == "FALSE" || s == "0") return false;
    throw ConversionError("cannot convert '" + std::string(s) + "' to bool");
  }
};

template <class T>
struct Convert<T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>>> {
  static constexpr bool available = true;
  static T fromString(std::string_view s) {
    T v{};
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size() || s.empty())
      throw ConversionError("cannot convert '" + std::string(s) + "' to an integer");
    return v;
  }
};

template <class T>
struct Convert<T, std::enable_if_t<std::is_floating_point_v<T>>> {
  static constexpr bool available = true;
  static T fromString(std::string_view s) {
    T v{};
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size() || s.empty())
      throw ConversionError("cannot convert '" + std::string(s) + "' to a floating-point number");
    return v;
  }
};

template <>
struct Convert<Value> {
  static constexpr bool available = true;
  static Value fromString(std::string_view s) { return parseLiteral(s); }
};

/// Types the script language can read and write (through Value).
template <class T>
constexpr bool kScriptType = std::is_same_v<T, Value> || std::is_same_v<T, bool> || std::is_same_v<T, std::string> ||
                             std::is_arithmetic_v<T>;

/// Value -> T for script types; returns false when the value does not fit (e.g. 1.5 into an int).
template <class T>
bool fromValue(const Value& v, T& out) {
  if constexpr (std::is_same_v<T, Value>) {
    out = v;
    return true;
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (auto* s = std::get_if<std::string>(&v)) {
      out = *s;
      return true;
    }
    return false;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (auto* b = std::get_if<bool>(&v)) { out = *b; return true; }
    if (auto* i = std::get_if<std::int64_t>(&v)) {
      if (*i == 0 || *i == 1) { out = (*i == 1); return true; }
    }
    return false;
  } else if constexpr (std::is_integral_v<T>) {
    if (auto* i = std::get_if<std::int64_t>(&v)) { out = static_cast<T>(*i); return true; }
    if (auto* d = std::get_if<double>(&v)) {
      if (static_cast<double>(static_cast<std::int64_t>(*d)) == *d) { out = static_cast<T>(*d); return true; }
      return false;
    }
    if (auto* b = std::get_if<bool>(&v)) { out = static_cast<T>(*b); return true; }
    if (auto* s = std::get_if<std::string>(&v)) {
      try { out = Convert<T>::fromString(*s); return true; } catch (const ConversionError&) { return false; }
    }
    return false;
  } else if constexpr (std::is_floating_point_v<T>) {
    if (auto* d = std::get_if<double>(&v)) { out = static_cast<T>(*d); return true; }
    if (auto* i = std::get_if<std::int64_t>(&v)) { out = static_cast<T>(*i); return true; }
    if (auto* s = std::get_if<std::string>(&v)) {
      try { out = Convert<T>::fromString(*s); return true; } catch (const ConversionError&) { return false; }
    }
    return false;
  } else {
    return false;
  }
}

template <class T>
Value toValue(const T& v) {
  if constexpr (std::is_same_v<T, Value>) return v;
  else if constexpr (std::is_same_v<T, std::string>) return Value(v);
  else if constexpr (std::is_same_v<T, bool>) return Value(v);
  else if constexpr (std::is_integral_v<T>) return Value(static_cast<std::int64_t>(v));
  else if constexpr (std::is_floating_point_v<T>) return Value(static_cast<double>(v));
  else return Value();
}

std::string demangle(const char* mangled);

template <class T>
std::string typeName() {
  if constexpr (std::is_same_v<T, std::string>) return "std::string";
  else if constexpr (std::is_same_v<T, Value>) return "any";
  else return demangle(typeid(T).name());
}

}  // namespace cairn::bt
