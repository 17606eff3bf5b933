#include <cmath>
#include <map>
#include <mutex>
#include <ostream>
#include <sstream>

#include "cairn/msgs/type_support_impl.hpp"

namespace cairn::msgs {

void* Scratch::alloc(std::size_t bytes) {
  blocks_.push_back(std::make_unique<std::byte[]>(bytes == 0 ? 1 : bytes));  // value-initialised: zeros
  return blocks_.back().get();
}

namespace {
struct Registry {
  std::mutex mu;
  std::map<std::string, const TypeSupport*, std::less<>> by_name;
};
Registry& registry() {
  static Registry r;
  return r;
}
}  // namespace

Registrar::Registrar(const TypeSupport* ts) {
  auto& r = registry();
  std::lock_guard lock(r.mu);
  r.by_name[ts->dds_type_name] = ts;
  r.by_name[ts->ros_type_name] = ts;
}

const TypeSupport* find_type_support(std::string_view name) {
  auto& r = registry();
  std::lock_guard lock(r.mu);
  auto it = r.by_name.find(name);
  return it == r.by_name.end() ? nullptr : it->second;
}

std::vector<const TypeSupport*> all_type_supports() {
  auto& r = registry();
  std::lock_guard lock(r.mu);
  std::vector<const TypeSupport*> out;
  for (const auto& [name, ts] : r.by_name) {
    if (name == ts->dds_type_name) out.push_back(ts);
  }
  return out;
}

std::string to_text(const TypeSupport& ts, const void* msg) {
  std::ostringstream o;
  ts.print(msg, o);
  return o.str();
}

namespace gen {
void print_indent(std::ostream& o, int indent) {
  for (int i = 0; i < indent; ++i) o.put(' ');
}
void print_scalar(std::ostream& o, double v) {
  if (std::isfinite(v)) {
    std::ostringstream s;
    s << std::setprecision(17) << v;
    o << s.str();
  } else {
    o << (std::isnan(v) ? ".nan" : (v > 0 ? ".inf" : "-.inf"));
  }
}
void print_scalar(std::ostream& o, float v) {
  if (std::isfinite(v)) {
    std::ostringstream s;
    s << std::setprecision(9) << v;
    o << s.str();
  } else {
    o << (std::isnan(v) ? ".nan" : (v > 0 ? ".inf" : "-.inf"));
  }
}
void print_string(std::ostream& o, const std::string& s) {
  o << '"';
  for (char c : s) {
    switch (c) {
      case '"': o << "\\\""; break;
      case '\\': o << "\\\\"; break;
      case '\n': o << "\\n"; break;
      case '\t': o << "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          o << "\\x" << std::hex << std::setw(2) << std::setfill('0') << int(c) << std::dec;
        } else {
          o << c;
        }
    }
  }
  o << '"';
}
}  // namespace gen
}  // namespace cairn::msgs
