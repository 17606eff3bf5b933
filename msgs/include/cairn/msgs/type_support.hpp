// Type support: what the runtime needs to move a generated C++ message across the DDS boundary.
// Components only see the C++ structs; this header pulls in no DDS header.
#ifndef CAIRN_MSGS_TYPE_SUPPORT_HPP
#define CAIRN_MSGS_TYPE_SUPPORT_HPP

#include <cstddef>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

struct dds_topic_descriptor;

namespace cairn::msgs {

/// Temporaries of one C++ -> C conversion (arrays of nested structs, string tables). Memory is
/// zero-initialised and lives until clear() or destruction.
class Scratch {
 public:
  void* alloc(std::size_t bytes);
  void clear() { blocks_.clear(); }

 private:
  std::vector<std::unique_ptr<std::byte[]>> blocks_;
};

/// Operations on one message type, generated from its IDL by msgs/cmake/idl2cpp.py.
struct TypeSupport {
  const char* dds_type_name;  ///< e.g. "std_msgs::msg::dds_::String_" (what DDS matches on)
  const char* ros_type_name;  ///< e.g. "std_msgs/msg/String"
  const dds_topic_descriptor* descriptor;  ///< idlc's descriptor of the C type
  std::size_t c_size;                      ///< sizeof the idlc C struct
  /// Fills a zero-initialised C sample from a C++ message. Sequences of primitives and strings borrow
  /// the C++ message's buffers (no copy); the C sample is valid while `cpp` and `scratch` live.
  /// Throws std::length_error when a bounded sequence is too long.
  void (*to_c)(const void* cpp, void* c, Scratch& scratch);
  /// Copies a C sample (as delivered by dds_take) into a C++ message.
  void (*from_c)(const void* c, void* cpp);
  void* (*create)();
  void (*destroy)(void*);
  /// Readable YAML-like text, as `cairn topic echo` prints it.
  void (*print)(const void* cpp, std::ostream& out);
};

template <class T>
const TypeSupport& type_support();

/// Looks a type up by DDS name ("pkg::msg::dds_::T_") or ROS name ("pkg/msg/T"); nullptr if unknown.
const TypeSupport* find_type_support(std::string_view name);
std::vector<const TypeSupport*> all_type_supports();

struct Registrar {
  explicit Registrar(const TypeSupport* ts);
};

namespace gen {
struct Adl {};
}  // namespace gen

std::string to_text(const TypeSupport& ts, const void* msg);

template <class T>
std::string to_text(const T& msg) {
  return to_text(type_support<T>(), &msg);
}

}  // namespace cairn::msgs

#endif  // CAIRN_MSGS_TYPE_SUPPORT_HPP
