#include "cairn/parameters.hpp"

#include <cmath>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "cairn/strict_number.hpp"

namespace cairn {

ParameterType type_of(const ParameterValue& v) { return static_cast<ParameterType>(v.index()); }

const char* type_name(ParameterType t) {
  switch (t) {
    case ParameterType::NotSet: return "not set";
    case ParameterType::Bool: return "bool";
    case ParameterType::Integer: return "integer";
    case ParameterType::Double: return "double";
    case ParameterType::String: return "string";
    case ParameterType::ByteArray: return "byte array";
    case ParameterType::BoolArray: return "bool array";
    case ParameterType::IntegerArray: return "integer array";
    case ParameterType::DoubleArray: return "double array";
    case ParameterType::StringArray: return "string array";
  }
  return "?";
}

namespace {
template <class T>
void put(std::ostream& o, const T& v) {
  if constexpr (std::is_same_v<T, bool>) {
    o << (v ? "true" : "false");
  } else if constexpr (std::is_same_v<T, std::string>) {
    YAML::Emitter e;
    e << YAML::DoubleQuoted << v;
    o << e.c_str();
  } else if constexpr (std::is_same_v<T, double>) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    std::string t = s.str();
    if (t.find_first_of(".eEn") == std::string::npos) t += ".0";  // stays a double when read back
    o << t;
  } else if constexpr (std::is_same_v<T, uint8_t>) {
    o << static_cast<int>(v);
  } else {
    o << v;
  }
}
}  // namespace

std::string to_string(const ParameterValue& v) {
  std::ostringstream o;
  std::visit(
      [&](const auto& x) {
        using X = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<X, std::monostate>) {
          o << "null";
        } else if constexpr (requires { x.begin(); } && !std::is_same_v<X, std::string>) {
          o << "[";
          bool first = true;
          for (auto e : x) {
            if (!first) o << ", ";
            first = false;
            put(o, static_cast<typename X::value_type>(e));
          }
          o << "]";
        } else {
          put(o, x);
        }
      },
      v);
  return o.str();
}

namespace {
ParameterValue scalar_from_yaml(const YAML::Node& n) {
  const std::string& s = n.Scalar();
  if (n.Tag() == "!" ) return s;  // quoted string
  bool b;
  if (YAML::convert<bool>::decode(n, b) && (s == "true" || s == "false" || s == "True" || s == "False")) return b;
  // A plain scalar that is a whole number is an integer, one that is a finite number a double, anything else
  // (also "nan", "inf", "0x10", "5 m") a string, which the parameter's declared type then rejects by name.
  if (const auto i = strict_number::parse_integer(s)) return static_cast<int64_t>(*i);
  if (const auto d = strict_number::parse_finite(s)) return *d;
  return s;
}
}  // namespace

ParameterValue parameter_from_yaml(const YAML::Node& n);

ParameterValue parameter_from_yaml(const YAML::Node& n) {
  if (n.IsNull()) return std::monostate{};
  if (n.IsScalar()) return scalar_from_yaml(n);
  if (n.IsSequence()) {
    std::vector<ParameterValue> elems;
    for (const auto& e : n) {
      if (!e.IsScalar()) throw ParameterError("parameter arrays hold scalars only");
      elems.push_back(scalar_from_yaml(e));
    }
    if (elems.empty()) return std::vector<std::string>{};
    auto all = [&](auto pred) { return std::all_of(elems.begin(), elems.end(), pred); };
    if (all([](auto& e) { return std::holds_alternative<bool>(e); })) {
      std::vector<bool> out;
      for (auto& e : elems) out.push_back(std::get<bool>(e));
      return out;
    }
    if (all([](auto& e) { return std::holds_alternative<int64_t>(e); })) {
      std::vector<int64_t> out;
      for (auto& e : elems) out.push_back(std::get<int64_t>(e));
      return out;
    }
    if (all([](auto& e) { return std::holds_alternative<int64_t>(e) || std::holds_alternative<double>(e); })) {
      std::vector<double> out;
      for (auto& e : elems) {
        out.push_back(std::holds_alternative<double>(e) ? std::get<double>(e) : double(std::get<int64_t>(e)));
      }
      return out;
    }
    std::vector<std::string> out;
    for (const auto& e : n) out.push_back(e.Scalar());
    return out;
  }
  throw ParameterError("a parameter value must be a scalar or a list of scalars");
}

ParameterValue parse_parameter_text(const std::string& text) {
  YAML::Node n;
  try {
    n = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ParameterError("cannot parse parameter value '" + text + "': " + e.msg);
  }
  return parameter_from_yaml(n);
}

std::optional<std::string> ParameterStore::check(const std::string& name, ParameterType type,
                                                 const ParameterDescriptor& d, ParameterValue& v) const {
  // lossless widening: integer -> double, integer array -> double array
  if (type == ParameterType::Double && std::holds_alternative<int64_t>(v)) v = static_cast<double>(std::get<int64_t>(v));
  if (type == ParameterType::DoubleArray && std::holds_alternative<std::vector<int64_t>>(v)) {
    const auto& iv = std::get<std::vector<int64_t>>(v);
    v = std::vector<double>(iv.begin(), iv.end());
  }
  // an empty YAML list parses as a string array; accept it for every array type
  if (auto* sv = std::get_if<std::vector<std::string>>(&v); sv && sv->empty()) {
    switch (type) {
      case ParameterType::ByteArray: v = std::vector<uint8_t>{}; break;
      case ParameterType::BoolArray: v = std::vector<bool>{}; break;
      case ParameterType::IntegerArray: v = std::vector<int64_t>{}; break;
      case ParameterType::DoubleArray: v = std::vector<double>{}; break;
      default: break;
    }
  }
  if (type_of(v) != type) {
    return "parameter '" + name + "' expects " + type_name(type) + ", got " + type_name(type_of(v)) + " (" +
           to_string(v) + ")";
  }
  auto in_range = [&](double x) -> std::optional<std::string> {
    if ((d.min && x < *d.min) || (d.max && x > *d.max) || std::isnan(x)) {
      // Bounds as the value is printed (shortest form): std::to_string gave [0.000000, 5.000000] and turned a
      // bound of 1e-7 into 0.000000.
      std::ostringstream o;
      o << "parameter '" << name << "' = " << x << " is outside [";
      if (d.min) o << *d.min;
      else o << "-inf";
      o << ", ";
      if (d.max) o << *d.max;
      else o << "inf";
      o << "]";
      return o.str();
    }
    return std::nullopt;
  };
  if (auto* p = std::get_if<int64_t>(&v)) return in_range(static_cast<double>(*p));
  if (auto* p = std::get_if<double>(&v)) return in_range(*p);
  if (auto* p = std::get_if<std::vector<double>>(&v)) {
    for (double x : *p)
      if (auto e = in_range(x)) return e;
  }
  if (auto* p = std::get_if<std::vector<int64_t>>(&v)) {
    for (auto x : *p)
      if (auto e = in_range(static_cast<double>(x))) return e;
  }
  return std::nullopt;
}

ParameterValue ParameterStore::declare(const std::string& name, ParameterType type, const ParameterValue& def,
                                       const ParameterDescriptor& desc) {
  std::lock_guard l(mu_);
  if (params_.count(name)) throw ParameterError("parameter '" + name + "' is declared twice");
  ParameterValue v = def;
  auto it = overrides_.find(name);
  if (it != overrides_.end()) {
    v = it->second;
    overrides_.erase(it);
  }
  if (auto err = check(name, type, desc, v)) throw ParameterError(*err);
  params_[name] = Entry{type, v, desc};
  return v;
}

bool ParameterStore::has(const std::string& name) const {
  std::lock_guard l(mu_);
  return params_.count(name) > 0;
}

ParameterValue ParameterStore::get(const std::string& name) const {
  std::lock_guard l(mu_);
  auto it = params_.find(name);
  if (it == params_.end()) throw ParameterError("parameter '" + name + "' is not declared");
  return it->second.value;
}

std::optional<std::string> ParameterStore::set(const std::string& name, const ParameterValue& value) {
  std::vector<OnSet> cbs;
  ParameterValue v = value;
  {
    std::lock_guard l(mu_);
    auto it = params_.find(name);
    if (it == params_.end()) return "parameter '" + name + "' is not declared";
    if (it->second.desc.read_only) return "parameter '" + name + "' is read-only";
    if (auto err = check(name, it->second.type, it->second.desc, v)) return err;
    cbs = on_set_;
  }
  for (auto& cb : cbs) {
    if (auto reason = cb(name, v)) return reason;
  }
  std::lock_guard l(mu_);
  params_[name].value = v;
  return std::nullopt;
}

std::vector<std::string> ParameterStore::names() const {
  std::lock_guard l(mu_);
  std::vector<std::string> out;
  for (const auto& [k, e] : params_) out.push_back(k);
  return out;
}

std::optional<ParameterDescriptor> ParameterStore::descriptor(const std::string& name) const {
  std::lock_guard l(mu_);
  auto it = params_.find(name);
  if (it == params_.end()) return std::nullopt;
  return it->second.desc;
}

std::optional<ParameterType> ParameterStore::declared_type(const std::string& name) const {
  std::lock_guard l(mu_);
  auto it = params_.find(name);
  if (it == params_.end()) return std::nullopt;
  return it->second.type;
}

std::vector<std::string> ParameterStore::unused_overrides() const {
  std::lock_guard l(mu_);
  std::vector<std::string> out;
  for (const auto& [k, v] : overrides_) out.push_back(k);
  return out;
}

void ParameterStore::on_set(OnSet cb) {
  std::lock_guard l(mu_);
  on_set_.push_back(std::move(cb));
}

}  // namespace cairn
