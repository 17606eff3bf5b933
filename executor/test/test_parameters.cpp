#include <gtest/gtest.h>

#include "cairn/node.hpp"
#include "rcl_interfaces/srv/GetParameters.hpp"
#include "rcl_interfaces/srv/SetParameters.hpp"
#include "cairn/parameter_msgs.hpp"
#include "cairn/test_support.hpp"

using namespace std::chrono_literals;

TEST(Parameters, DefaultsOverridesAndRanges) {
  cairn::ParameterStore store({{"rate", int64_t(20)}, {"name", std::string("x")}, {"bogus", true}});
  EXPECT_EQ(std::get<double>(store.declare("rate", cairn::ParameterType::Double, 10.0, {"", 0.0, 100.0, false})), 20.0)
      << "an integer override widens to double";
  EXPECT_THROW(store.declare("name", cairn::ParameterType::Integer, int64_t(1), {}), cairn::ParameterError);
  EXPECT_EQ(store.unused_overrides(), std::vector<std::string>{"bogus"});
  EXPECT_TRUE(store.set("rate", 150.0).has_value()) << "out of range must be rejected";
  EXPECT_FALSE(store.set("rate", 50.0).has_value());
  EXPECT_EQ(std::get<double>(store.get("rate")), 50.0);
  EXPECT_TRUE(store.set("nope", 1.0).has_value());
  EXPECT_THROW(store.declare("rate", cairn::ParameterType::Double, 1.0, {}), cairn::ParameterError);
}

TEST(Parameters, TextParsing) {
  EXPECT_EQ(cairn::parse_parameter_text("3"), cairn::ParameterValue(int64_t(3)));
  EXPECT_EQ(cairn::parse_parameter_text("2.5"), cairn::ParameterValue(2.5));
  EXPECT_EQ(cairn::parse_parameter_text("true"), cairn::ParameterValue(true));
  EXPECT_EQ(cairn::parse_parameter_text("hello"), cairn::ParameterValue(std::string("hello")));
  EXPECT_EQ(cairn::parse_parameter_text("\"42\""), cairn::ParameterValue(std::string("42")));
  EXPECT_EQ(cairn::parse_parameter_text("[1, 2.5]"), cairn::ParameterValue(std::vector<double>{1.0, 2.5}));
  EXPECT_EQ(cairn::to_string(cairn::ParameterValue(2.0)), "2.0");
  EXPECT_THROW(cairn::parse_parameter_text("{a: 1}"), cairn::ParameterError);
}

TEST(Parameters, RemoteGetAndSetOverServices) {
  cairn::Executor exec(cairn::Executor::Options{2});
  cairn::NodeOptions o("tuned", &exec);
  o.parameter_overrides["gain"] = 2.0;
  cairn::Node node(o);
  EXPECT_EQ(node.declare_parameter<double>("gain", 1.0, {"", 0.0, 10.0, false}), 2.0);
  cairn::testing::Spinner spinner(exec);  // stops and joins on every way out (an ASSERT returning early too)
  auto ctx2 = cairn::Context::create();
  cairn::Executor exec2;
  cairn::NodeOptions co("cli", &exec2);
  co.context = ctx2;
  co.start_parameter_services = false;
  cairn::Node cli(co);
  auto get = cli.create_client<rcl_interfaces::srv::GetParameters_Request, rcl_interfaces::srv::GetParameters_Response>(
      "/tuned/get_parameters");
  auto set = cli.create_client<rcl_interfaces::srv::SetParameters_Request, rcl_interfaces::srv::SetParameters_Response>(
      "/tuned/set_parameters");
  rcl_interfaces::srv::SetParameters_Request sreq;
  rcl_interfaces::msg::Parameter p;
  p.name = "gain";
  p.value = cairn::to_parameter_msg(20.0);  // out of range
  sreq.parameters.push_back(p);
  p.value = cairn::to_parameter_msg(5.0);
  sreq.parameters.push_back(p);
  auto sresp = set->call(sreq, 10s);
  ASSERT_TRUE(sresp.has_value());
  ASSERT_EQ(sresp->results.size(), 2u);
  EXPECT_FALSE(sresp->results[0].successful);
  EXPECT_NE(sresp->results[0].reason.find("outside"), std::string::npos);
  EXPECT_TRUE(sresp->results[1].successful);
  rcl_interfaces::srv::GetParameters_Request greq;
  greq.names = {"gain", "use_sim_time"};
  auto gresp = get->call(greq, 10s);
  ASSERT_TRUE(gresp.has_value());
  ASSERT_EQ(gresp->values.size(), 2u);
  EXPECT_EQ(cairn::from_parameter_msg(gresp->values[0]), cairn::ParameterValue(5.0));
  EXPECT_EQ(cairn::from_parameter_msg(gresp->values[1]), cairn::ParameterValue(false));
}
