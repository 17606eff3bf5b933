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

namespace {
// The generated print functions take no options; to_text sets the list limit for its own call on this thread.
thread_local std::size_t t_print_max_elements = kPrintMaxElements;
}  // namespace

namespace gen {
std::size_t print_max_elements() { return t_print_max_elements; }
}  // namespace gen

std::string to_text(const TypeSupport& ts, const void* msg, std::size_t max_elements) {
  struct Restore {
    std::size_t previous;
    ~Restore() { t_print_max_elements = previous; }
  } restore{t_print_max_elements};
  t_print_max_elements = max_elements;
  std::ostringstream o;
  ts.print(msg, o);
  return o.str();
}

std::vector<unsigned char> serialize(const TypeSupport& ts, const void* msg) {
  const std::size_t n = ts.cdr_size(msg);
  const std::size_t pad = (4 - n % 4) % 4;
  std::vector<unsigned char> out(4 + n + pad, 0);
  out[1] = 0x01;  // CDR_LE
  out[3] = static_cast<unsigned char>(pad);
  ts.cdr_write(msg, out.data() + 4);
  return out;
}

void deserialize(const TypeSupport& ts, const unsigned char* data, std::size_t size, void* msg) {
  if (size < 4) throw CdrError("serialized sample shorter than its encapsulation header");
  if (data[0] != 0 || data[1] > 1) {
    throw CdrError("unsupported CDR encapsulation " + std::to_string(data[0]) + "," + std::to_string(data[1]) +
                   " (cairn types are XCDR1: CDR_BE or CDR_LE)");
  }
  ts.cdr_read(data + 4, size - 4, data[1] == 0, msg);
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
