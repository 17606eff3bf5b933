// A plain C program built with idlc from msgs/*.idl (linked only against libddsc) receives what a cairn
// node publishes and sends back data that the cairn node receives: the CDR bytes and type names match.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include "cairn/node.hpp"
#include "cairn/process.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"

using namespace std::chrono_literals;
using sensor_msgs::msg::LaserScan;

TEST(IdlInterop, PlainCIdlcProgramAndCairnNodeExchangeLaserScans) {
  cairn::Executor exec;
  cairn::NodeOptions o("interop", &exec);
  o.start_parameter_services = false;
  cairn::Node node(o);
  std::vector<LaserScan> back;
  auto sub = node.create_subscription<LaserScan>("/interop/scan_out", cairn::QoS{},
                                                 [&](const LaserScan& s) { back.push_back(s); });
  auto pub = node.create_publisher<LaserScan>("/interop/scan_in", cairn::QoS{});
  const pid_t peer = cairn::spawn_process({C_PEER_EXE, std::to_string(node.context().domain_id()), "3"});
  ASSERT_TRUE(exec.spin_until([&] { return pub->inter_process_subscription_count() == 1 &&
                                           sub->publisher_count_inter_process() == 1; }, 20s))
      << "the C program's reader/writer were not matched (type name or QoS mismatch?)";
  for (int i = 0; i < 3; ++i) {
    LaserScan s;
    s.header.frame_id = "laser" + std::to_string(i);
    s.header.stamp.sec = 100 + i;
    s.header.stamp.nanosec = 5;
    s.angle_min = -1.5f;
    s.angle_max = 1.5f;
    s.angle_increment = 0.5f;
    s.range_max = 30.f;
    s.ranges = {1.f, 2.f, float(i)};
    s.intensities = {7.f};
    pub->publish(s);
  }
  exec.spin_until([&] { return back.size() == 3; }, 20s);
  int status = 0;
  waitpid(peer, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cairn::describe_wait_status(status);
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].header.frame_id, "laser" + std::to_string(i) + "_c");
    EXPECT_EQ(back[i].header.stamp.sec, 100 + i);
    EXPECT_EQ(back[i].header.stamp.nanosec, 5u);
    EXPECT_EQ(back[i].angle_increment, 0.5f);
    EXPECT_EQ(back[i].ranges, (std::vector<float>{2.f, 4.f, 2.f * i}));
    EXPECT_EQ(back[i].intensities, std::vector<float>{7.f});
  }
}
