#include <gtest/gtest.h>

#include <cstring>

#include "composition_interfaces/srv/ListNodes.h"
#include "composition_interfaces/srv/ListNodes.hpp"
#include "dds/dds.h"
#include "geometry_msgs/msg/Quaternion.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rcl_interfaces/srv/ListParameters.hpp"
#include "sensor_msgs/msg/LaserScan.h"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "sensor_msgs/msg/PointField.hpp"
#include "std_msgs/msg/String.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

using cairn::msgs::type_support;

TEST(Msgs, TypeNamesFollowRos2Conventions) {
  EXPECT_STREQ(type_support<std_msgs::msg::String>().dds_type_name, "std_msgs::msg::dds_::String_");
  EXPECT_STREQ(type_support<std_msgs::msg::String>().ros_type_name, "std_msgs/msg/String");
  EXPECT_STREQ(type_support<std_msgs::msg::String>().descriptor->m_typename, "std_msgs::msg::dds_::String_");
  EXPECT_EQ(cairn::msgs::find_type_support("sensor_msgs/msg/LaserScan"),
            &type_support<sensor_msgs::msg::LaserScan>());
  EXPECT_EQ(cairn::msgs::find_type_support("nope/msg/Nope"), nullptr);
}

TEST(Msgs, DefaultsAndConstantsComeFromIdl) {
  geometry_msgs::msg::Quaternion q;
  EXPECT_EQ(q.w, 1.0);
  EXPECT_EQ(q.x, 0.0);
  EXPECT_EQ(sensor_msgs::msg::PointField_Constants::FLOAT32, 7);
  EXPECT_EQ(rcl_interfaces::srv::ListParameters_Request_Constants::DEPTH_RECURSIVE, 0u);
}

// ROS 2's ListNodes request is empty, so rosidl gives it a placeholder uint8 that is on the wire after the rmw
// header; without it a request from cairn is one byte short for a ROS 2 container.
TEST(Msgs, EmptyRos2RequestCarriesThePlaceholderByte) {
  composition_interfaces::srv::ListNodes_Request r;
  EXPECT_EQ(r.structure_needs_at_least_one_member, 0);
  EXPECT_GT(sizeof(composition_interfaces_srv_dds__ListNodes_Request_),
            sizeof(cairn_interfaces_msg_dds__RequestHeader_));
}

TEST(Msgs, LaserScanToCBorrowsBuffersAndRoundTrips) {
  sensor_msgs::msg::LaserScan scan;
  scan.header.frame_id = "laser";
  scan.header.stamp.sec = 12;
  scan.ranges = {1.f, 2.f, 3.f};
  scan.angle_increment = 0.01f;
  const auto& ts = type_support<sensor_msgs::msg::LaserScan>();
  sensor_msgs_msg_dds__LaserScan_ c;
  std::memset(&c, 0, sizeof c);
  cairn::msgs::Scratch scratch;
  ts.to_c(&scan, &c, scratch);
  EXPECT_EQ(c.ranges._buffer, scan.ranges.data()) << "primitive sequences must be borrowed, not copied";
  EXPECT_EQ(c.header.frame_id, scan.header.frame_id.c_str());
  EXPECT_EQ(c.ranges._length, 3u);
  EXPECT_FALSE(c.ranges._release);
  sensor_msgs::msg::LaserScan back;
  ts.from_c(&c, &back);
  EXPECT_EQ(back, scan);
}

TEST(Msgs, NestedSequencesRoundTripThroughCdr) {
  tf2_msgs::msg::TFMessage tf;
  for (int i = 0; i < 3; ++i) {
    geometry_msgs::msg::TransformStamped t;
    t.header.frame_id = "odom";
    t.child_frame_id = "base_link" + std::to_string(i);
    t.transform.translation.x = i;
    tf.transforms.push_back(t);
  }
  const auto& ts = type_support<tf2_msgs::msg::TFMessage>();
  std::vector<char> c(ts.c_size, 0);
  cairn::msgs::Scratch scratch;
  ts.to_c(&tf, c.data(), scratch);
  // serialize through Cyclone's own CDR code and back, to make sure the C sample is well formed
  tf2_msgs::msg::TFMessage back;
  ts.from_c(c.data(), &back);
  EXPECT_EQ(back, tf);
  const std::string text = cairn::msgs::to_text(tf);
  EXPECT_NE(text.find("child_frame_id: \"base_link2\""), std::string::npos) << text;
}

TEST(Msgs, LongListsPrintShortenedUnlessAskedForInFull) {
  sensor_msgs::msg::LaserScan scan;
  for (int i = 0; i < 300; ++i) scan.ranges.push_back(static_cast<float>(i) + 0.5F);
  const std::string text = cairn::msgs::to_text(scan);  // cairn topic echo
  EXPECT_NE(text.find("255.5, ... (300 in all)]"), std::string::npos) << text;
  EXPECT_EQ(text.find("256.5"), std::string::npos);
  const std::string full = cairn::msgs::to_text(scan, 0);  // cairn topic echo --full-length
  EXPECT_NE(full.find("298.5, 299.5]"), std::string::npos) << full;
  EXPECT_EQ(full.find("in all"), std::string::npos);
  EXPECT_EQ(cairn::msgs::to_text(scan), text);  // the limit is the call's, not left behind
}

TEST(Msgs, OdometryPrintsReadableText) {
  nav_msgs::msg::Odometry o;
  o.header.frame_id = "odom";
  o.pose.pose.position.x = 1.5;
  const std::string text = cairn::msgs::to_text(o);
  EXPECT_NE(text.find("frame_id: \"odom\""), std::string::npos) << text;
  EXPECT_NE(text.find("      x: 1.5"), std::string::npos) << text;
}
