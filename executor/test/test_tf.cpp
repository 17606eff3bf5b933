#include <gtest/gtest.h>

#include <cmath>

#include "cairn/container.hpp"
#include "cairn/tf.hpp"

using namespace std::chrono_literals;
using cairn::Time;
using cairn::TransformBuffer;

namespace {
geometry_msgs::msg::TransformStamped tf(const std::string& parent, const std::string& child, double sec, double x,
                                        double y, double yaw) {
  geometry_msgs::msg::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.header.stamp = cairn::to_stamp(Time::from_seconds(sec));
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.rotation.z = std::sin(yaw / 2);
  t.transform.rotation.w = std::cos(yaw / 2);
  return t;
}
}  // namespace

TEST(Tf, ChainsInvertsAndInterpolates) {
  TransformBuffer buf;
  buf.set_transform(tf("map", "odom", 10, 1, 0, 0), false);
  buf.set_transform(tf("map", "odom", 12, 3, 0, 0), false);
  buf.set_transform(tf("odom", "base_link", 10, 0, 0, M_PI / 2), false);
  buf.set_transform(tf("odom", "base_link", 12, 0, 0, M_PI / 2), false);
  buf.set_transform(tf("base_link", "laser", 0, 0.2, 0, 0), true);
  // laser origin in map at t=11: odom interpolated to x=2, base rotated 90 deg, laser 0.2 ahead -> (2, 0.2)
  const auto T = buf.lookup("map", "laser", Time::from_seconds(11));
  const Eigen::Vector3d p = T * Eigen::Vector3d::Zero();
  EXPECT_NEAR(p.x(), 2.0, 1e-9);
  EXPECT_NEAR(p.y(), 0.2, 1e-9);
  // the inverse direction
  const Eigen::Vector3d back = buf.lookup("laser", "map", Time::from_seconds(11)) * p;
  EXPECT_NEAR(back.norm(), 0.0, 1e-9);
  // latest common time = 12
  EXPECT_NEAR((buf.lookup("map", "laser", Time{0}) * Eigen::Vector3d::Zero()).x(), 3.0, 1e-9);
  // slerp halfway between 0 and 90 degrees
  buf.set_transform(tf("odom", "turret", 0, 0, 0, 0), false);
  buf.set_transform(tf("odom", "turret", 2, 0, 0, M_PI / 2), false);
  const auto half = buf.lookup("odom", "turret", Time::from_seconds(1));
  EXPECT_NEAR(half.q.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()))), 0, 1e-9);
}

TEST(Tf, ErrorsNameTheProblem) {
  TransformBuffer buf;
  buf.set_transform(tf("map", "odom", 10, 1, 0, 0), false);
  buf.set_transform(tf("world", "other", 10, 1, 0, 0), false);
  EXPECT_THROW(buf.lookup("map", "other", Time{0}), cairn::TransformError);
  try {
    buf.lookup("map", "odom", Time::from_seconds(20));
    FAIL();
  } catch (const cairn::TransformError& e) {
    EXPECT_NE(std::string(e.what()).find("extrapolate"), std::string::npos);
  }
  EXPECT_THROW(buf.set_transform(tf("a", "a", 1, 0, 0, 0), false), cairn::TransformError);
  auto bad = tf("a", "b", 1, NAN, 0, 0);
  EXPECT_THROW(buf.set_transform(bad, false), cairn::TransformError);
  EXPECT_FALSE(buf.can_transform("map", "nowhere", Time{0}));
}

TEST(Tf, StaticPublisherPublishesTheUrdfFixedJoints) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "tfc", loader);
  cairn::LoadRequest req("cairn::StaticTransformPublisher", "robot_description");
  req.parameters["urdf_file"] = std::string(CAIRN_SOURCE_ROOT) + "/urdf/cairn_service_robot.urdf";
  const auto r = mgr.load(req);
  ASSERT_TRUE(r.ok) << r.error;
  // a listener in another context: the transforms arrive over DDS, latched
  auto ctx2 = cairn::Context::create();
  cairn::NodeOptions o("listener", &exec);
  o.context = ctx2;
  cairn::Node node(o);
  auto buffer = std::make_shared<TransformBuffer>();
  cairn::TransformListener listener(node, buffer);
  exec.spin_until([&] { return buffer->can_transform("base_link", "laser", Time{0}); }, 10s);
  ASSERT_TRUE(buffer->can_transform("base_link", "laser", Time{0}));
  const auto T = buffer->lookup("base_footprint", "laser", Time{0});
  EXPECT_GT(std::abs((T * Eigen::Vector3d::Zero()).z()), 0.0) << "the laser sits above the footprint";

  cairn::LoadRequest bad("cairn::StaticTransformPublisher", "bad_description");
  bad.parameters["urdf_file"] = std::string("/nonexistent.urdf");
  const auto rb = mgr.load(bad);
  EXPECT_FALSE(rb.ok);
  EXPECT_NE(rb.error.find("urdf_file: cannot read '/nonexistent.urdf'"), std::string::npos) << rb.error;
}
