// libFuzzer target: the XML loader must reject bad input with LoadError only, and a tree that loads must tick
// without crashing (issue 8 "Bad input"). Corpus: test/fuzz/bt/xml.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "cairn/bt_executive/xml_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cairn::bt::NodeFactory factory;
  std::string_view text(reinterpret_cast<const char*>(data), size);
  cairn::bt::ManualScheduler sched;  // outlives the tree
  try {
    cairn::bt::Tree tree = cairn::bt::loadTreeFromText(factory, text);
    tree.setScheduler(&sched);
    for (int i = 0; i < 16; ++i) {
      if (tree.tickOnce() != cairn::bt::NodeStatus::RUNNING) break;
      if (auto t = sched.nextTimer()) sched.advanceTo(*t);
    }
    tree.haltTree();
  } catch (const cairn::bt::LoadError&) {
  }
  return 0;
}
