// libFuzzer target for the launch-spec parser: any input either parses or is rejected with a LaunchError
// (one line naming file:line); anything else (another exception, a crash, a hang) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cairn/launch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)cairn::parse_launch_spec_text(text, "fuzz.yaml");
  } catch (const cairn::LaunchError&) {
  }
  return 0;
}
