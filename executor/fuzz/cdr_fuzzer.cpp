// libFuzzer target for cairn's XCDR1 decoder (what every sample from the network goes through): the first
// input byte picks a message type, the rest is a serialized sample (encapsulation header + payload). Any
// input either decodes or is rejected with CdrError; a decoded message must re-serialize to bytes that
// decode and re-serialize to the very same bytes. Anything else (another exception, a crash, an ASan
// report, a huge allocation) is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "cairn/msgs/cdr.hpp"
#include "cairn/msgs/type_support.hpp"

using cairn::msgs::TypeSupport;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<const TypeSupport*> types = cairn::msgs::all_type_supports();
  if (size < 1 || types.empty()) return 0;
  const TypeSupport& ts = *types[data[0] % types.size()];
  void* msg = ts.create();
  try {
    cairn::msgs::deserialize(ts, data + 1, size - 1, msg);
  } catch (const cairn::msgs::CdrError&) {
    ts.destroy(msg);
    return 0;
  }
  const std::vector<unsigned char> once = cairn::msgs::serialize(ts, msg);
  void* again = ts.create();
  cairn::msgs::deserialize(ts, once.data(), once.size(), again);  // must not throw
  if (cairn::msgs::serialize(ts, again) != once) std::abort();
  ts.destroy(again);
  ts.destroy(msg);
  return 0;
}
