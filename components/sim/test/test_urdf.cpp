#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <cmath>

#include "cairn/sim/diff_drive.hpp"
#include "cairn/sim/laser.hpp"

using namespace cairn::sim;

TEST(RobotDescription, MatchesTheSimulatorDefaults) {
  const std::string path = std::string(CAIRN_SOURCE_ROOT) + "/urdf/cairn_service_robot.urdf";
  const auto model = urdf::parseURDFFile(path);
  ASSERT_TRUE(model) << path;
  EXPECT_EQ(model->getRoot()->name, "base_footprint");
  const DiffDriveConfig drive;
  const LaserConfig laser;
  const auto left = model->getJoint("left_wheel_joint"), right = model->getJoint("right_wheel_joint");
  ASSERT_TRUE(left && right);
  EXPECT_EQ(left->type, urdf::Joint::CONTINUOUS);
  EXPECT_NEAR(left->parent_to_joint_origin_transform.position.y - right->parent_to_joint_origin_transform.position.y,
              drive.wheel_separation, 1e-9);
  const auto wheel = model->getLink("left_wheel");
  ASSERT_TRUE(wheel && wheel->collision);
  const auto cyl = std::dynamic_pointer_cast<urdf::Cylinder>(wheel->collision->geometry);
  ASSERT_TRUE(cyl);
  EXPECT_NEAR(cyl->radius, drive.wheel_radius, 1e-9);
  // base_link sits at wheel-axle height above the footprint
  EXPECT_NEAR(model->getJoint("base_footprint_joint")->parent_to_joint_origin_transform.position.z, drive.wheel_radius, 1e-9);
  const auto base = model->getLink("base_link");
  const auto body = std::dynamic_pointer_cast<urdf::Cylinder>(base->collision->geometry);
  ASSERT_TRUE(body);
  EXPECT_NEAR(body->radius, drive.footprint_radius, 1e-9);
  const auto lj = model->getJoint("laser_joint");
  ASSERT_TRUE(lj);
  EXPECT_EQ(lj->child_link_name, laser.frame_id);
  EXPECT_EQ(lj->parent_link_name, "base_link");
  EXPECT_NEAR(lj->parent_to_joint_origin_transform.position.x, laser.mount.x, 1e-9);
  EXPECT_NEAR(lj->parent_to_joint_origin_transform.position.y, laser.mount.y, 1e-9);
  double roll, pitch, yaw;
  lj->parent_to_joint_origin_transform.rotation.getRPY(roll, pitch, yaw);
  EXPECT_NEAR(yaw, laser.mount.theta, 1e-9);
}
