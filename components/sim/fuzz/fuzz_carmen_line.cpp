// libFuzzer target for the CARMEN line parser (build with -DCAIRN_BUILD_FUZZERS=ON and clang).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "cairn/sim/carmen.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cairn::sim::CarmenRecord rec;
  std::string error;
  cairn::sim::parseCarmenLine(std::string_view(reinterpret_cast<const char*>(data), size), {}, rec, error);
  return 0;
}
