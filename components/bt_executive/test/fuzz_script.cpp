// libFuzzer target: the script parser reports ScriptError (with a column) and evaluation never throws.
// Corpus: test/fuzz/bt/script.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "cairn/bt_executive/script.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cairn::bt::ScriptEnums enums{{"OK", 0}, {"ERROR", 1}};
  std::string_view code(reinterpret_cast<const char*>(data), size);
  try {
    cairn::bt::Script s = cairn::bt::Script::parse(code, &enums);
    auto bb = cairn::bt::Blackboard::create();
    bb->set<int>("i", 3);
    bb->set<double>("d", 0.5);
    bb->set<std::string>("s", "text");
    bb->set<bool>("b", true);
    s.bind(*bb);
    cairn::bt::Value v;
    std::string err;
    s.evaluate(v, &err);
    s.evaluate(v, &err);
  } catch (const cairn::bt::ScriptError& e) {
    if (e.column > size + 1) __builtin_trap();  // columns must point into the script
  }
  return 0;
}
