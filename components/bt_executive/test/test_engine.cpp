#include <gtest/gtest.h>
#include "cairn/bt_executive/xml_loader.hpp"
using namespace cairn::bt;
TEST(Smoke, Loads) {
  NodeFactory f;
  auto t = loadTreeFromText(f, R"(<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence><AlwaysSuccess/></Sequence></BehaviorTree></root>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
}
