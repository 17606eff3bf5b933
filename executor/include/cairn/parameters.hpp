// Typed node parameters (the ROS 2 parameter types), with defaults, ranges and run-time get/set.
#ifndef CAIRN_PARAMETERS_HPP
#define CAIRN_PARAMETERS_HPP

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace YAML {
class Node;
}

namespace cairn {

using ParameterValue = std::variant<std::monostate, bool, int64_t, double, std::string, std::vector<uint8_t>,
                                    std::vector<bool>, std::vector<int64_t>, std::vector<double>,
                                    std::vector<std::string>>;

enum class ParameterType : uint8_t {  // rcl_interfaces/msg/ParameterType values
  NotSet = 0, Bool = 1, Integer = 2, Double = 3, String = 4, ByteArray = 5, BoolArray = 6, IntegerArray = 7,
  DoubleArray = 8, StringArray = 9
};

ParameterType type_of(const ParameterValue& v);
const char* type_name(ParameterType t);
/// YAML-ish text: true, 3, 2.5, "text" (quoted only when needed), [1, 2]
std::string to_string(const ParameterValue& v);
/// Parses YAML scalar/flow-sequence text ("3", "2.5", "true", "abc", "[1, 2]") into the natural type.
ParameterValue parse_parameter_text(const std::string& text);
/// The same from a parsed YAML node (launch specs); throws ParameterError for maps and nested lists.
ParameterValue parameter_from_yaml(const YAML::Node& n);

template <class T>
constexpr ParameterType parameter_type_of() {
  if constexpr (std::is_same_v<T, bool>) return ParameterType::Bool;
  else if constexpr (std::is_integral_v<T>) return ParameterType::Integer;
  else if constexpr (std::is_floating_point_v<T>) return ParameterType::Double;
  else if constexpr (std::is_same_v<T, std::string>) return ParameterType::String;
  else if constexpr (std::is_same_v<T, std::vector<uint8_t>>) return ParameterType::ByteArray;
  else if constexpr (std::is_same_v<T, std::vector<bool>>) return ParameterType::BoolArray;
  else if constexpr (std::is_same_v<T, std::vector<int64_t>>) return ParameterType::IntegerArray;
  else if constexpr (std::is_same_v<T, std::vector<double>>) return ParameterType::DoubleArray;
  else if constexpr (std::is_same_v<T, std::vector<std::string>>) return ParameterType::StringArray;
  else static_assert(sizeof(T) == 0, "unsupported parameter type");
}

struct ParameterDescriptor {
  std::string description;
  std::optional<double> min, max;  ///< inclusive range for numbers (and each element of numeric arrays)
  bool read_only = false;
};

class ParameterError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A node's parameters. Thread-safe.
class ParameterStore {
 public:
  explicit ParameterStore(std::map<std::string, ParameterValue> overrides = {}) : overrides_(std::move(overrides)) {}

  /// Declares `name` of type `type`; the value is the override given at start-up (launch params), converted
  /// int -> double where that is lossless, else `def`. Throws ParameterError on a type or range violation
  /// or a second declaration.
  ParameterValue declare(const std::string& name, ParameterType type, const ParameterValue& def,
                         const ParameterDescriptor& desc);
  bool has(const std::string& name) const;
  ParameterValue get(const std::string& name) const;  // throws ParameterError if undeclared
  /// Validates and sets; runs on-set callbacks, which may reject with a reason. Returns the reason on failure.
  std::optional<std::string> set(const std::string& name, const ParameterValue& v);
  std::vector<std::string> names() const;
  std::optional<ParameterDescriptor> descriptor(const std::string& name) const;
  std::optional<ParameterType> declared_type(const std::string& name) const;
  /// Overrides that no declare() consumed (unknown parameters in a launch spec).
  std::vector<std::string> unused_overrides() const;
  using OnSet = std::function<std::optional<std::string>(const std::string&, const ParameterValue&)>;
  void on_set(OnSet cb);

 private:
  std::optional<std::string> check(const std::string& name, ParameterType type, const ParameterDescriptor& d,
                                   ParameterValue& v) const;
  struct Entry {
    ParameterType type;
    ParameterValue value;
    ParameterDescriptor desc;
  };
  mutable std::mutex mu_;
  std::map<std::string, ParameterValue> overrides_;
  std::map<std::string, Entry> params_;
  std::vector<OnSet> on_set_;
};

template <class T>
T parameter_as(const ParameterValue& v, const std::string& name) {
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    if (auto* p = std::get_if<int64_t>(&v)) return static_cast<T>(*p);
  } else if constexpr (std::is_floating_point_v<T>) {
    if (auto* p = std::get_if<double>(&v)) return static_cast<T>(*p);
  } else {
    if (auto* p = std::get_if<T>(&v)) return *p;
  }
  throw ParameterError("parameter '" + name + "' is of type " + type_name(type_of(v)));
}

}  // namespace cairn

#endif  // CAIRN_PARAMETERS_HPP
