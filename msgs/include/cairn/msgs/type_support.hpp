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
  /// In-place lifetime of a C++ message in caller-provided storage of cpp_size bytes (DDS sample arrays).
  std::size_t cpp_size;
  void (*construct)(void* at);
  void (*destruct)(void* at);
  /// XCDR1 codec (cairn/msgs/cdr.hpp) straight between the C++ message and the serialized payload, i.e. the
  /// bytes after the 4-byte encapsulation header. cdr_size throws std::length_error when a bounded sequence
  /// is too long; cdr_write writes exactly cdr_size() bytes; cdr_read validates every length against the
  /// buffer and throws CdrError on malformed input (`big_endian`: CDR_BE encapsulation).
  std::size_t (*cdr_size)(const void* cpp);
  void (*cdr_write)(const void* cpp, unsigned char* payload);
  void (*cdr_read)(const unsigned char* payload, std::size_t size, bool big_endian, void* cpp);
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

/// Readable YAML-like text (`cairn topic echo`). A list of numbers or strings longer than `max_elements` ends with
/// "... (N in all)" after that many; 0 prints every element (`cairn topic echo --full-length`).
inline constexpr std::size_t kPrintMaxElements = 256;
std::string to_text(const TypeSupport& ts, const void* msg, std::size_t max_elements = kPrintMaxElements);

/// The serialized sample as it goes on the wire: encapsulation header (CDR_LE) + XCDR1 payload, padded to a
/// multiple of 4 with the padding count in the header's options (as Cyclone's own serializer does).
std::vector<unsigned char> serialize(const TypeSupport& ts, const void* msg);
/// Parses a serialized sample (CDR_LE or CDR_BE encapsulation) into `msg`; throws CdrError when malformed.
void deserialize(const TypeSupport& ts, const unsigned char* data, std::size_t size, void* msg);

template <class T>
std::string to_text(const T& msg, std::size_t max_elements = kPrintMaxElements) {
  return to_text(type_support<T>(), &msg, max_elements);
}

}  // namespace cairn::msgs

#endif  // CAIRN_MSGS_TYPE_SUPPORT_HPP
