#include <gtest/gtest.h>

#include <random>

#include "cairn/people_tracking/assignment.hpp"
#include "cairn/people_tracking/tracker.hpp"

using namespace cairn::people_tracking;

namespace {
PersonDetection det(const Eigen::Vector2d& p, double sigma = 0.05) {
  PersonDetection d;
  d.position = p;
  d.covariance = sigma * sigma * Eigen::Matrix2d::Identity();
  d.confidence = 0.9;
  d.legs = 2;
  d.leg_separation = 0.25;
  return d;
}
const Track* nearest(const std::vector<Track>& tracks, const Eigen::Vector2d& p) {
  const Track* best = nullptr;
  for (const auto& t : tracks)
    if (!best || (t.position() - p).norm() < (best->position() - p).norm()) best = &t;
  return best;
}
}  // namespace

TEST(Assignment, SolvesSquareAndRectangularProblems) {
  Eigen::MatrixXd c(3, 3);
  c << 4, 1, 3, 2, 0, 5, 3, 2, 2;
  EXPECT_EQ(solveAssignment(c), (std::vector<int>{1, 0, 2}));  // 1 + 2 + 2 = 5
  Eigen::MatrixXd r(2, 3);
  r << 5, 1, 9, 1, 5, 9;
  EXPECT_EQ(solveAssignment(r), (std::vector<int>{1, 0}));
  EXPECT_EQ(solveAssignment(Eigen::MatrixXd(r.transpose())), (std::vector<int>{1, 0, -1}));
  Eigen::MatrixXd f(2, 2);
  f << 1e9, 1, 1e9, 2;  // both rows want column 1; row 0 wins (cheaper), row 1 stays unassigned
  EXPECT_EQ(solveAssignment(f, 1e9), (std::vector<int>{1, -1}));
  EXPECT_TRUE(solveAssignment(Eigen::MatrixXd(0, 3)).empty());
}

TEST(Tracker, ConstantVelocityTargetIsConfirmedAndItsVelocityEstimated) {
  PeopleTracker tracker;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n(0.0, 0.05);
  const Eigen::Vector2d v(1.0, 0.5);
  int id = -1;
  for (int k = 0; k <= 40; ++k) {
    const double t = 0.1 * k;
    const Eigen::Vector2d p = Eigen::Vector2d(1, 1) + v * t;
    tracker.updateInFrame(t, {det(p + Eigen::Vector2d(n(rng), n(rng)))});
    const auto confirmed = tracker.confirmedTracks();
    const int needed = tracker.params().confirm_hits;  // scans until confirmation
    if (k + 1 < needed) {
      EXPECT_TRUE(confirmed.empty());
    } else {
      ASSERT_EQ(confirmed.size(), 1u) << k;
      if (id < 0) id = confirmed[0].id;
      EXPECT_EQ(confirmed[0].id, id);
    }
  }
  const Track t = tracker.confirmedTracks().at(0);
  EXPECT_LT((t.velocity() - v).norm(), 0.15);
  EXPECT_LT((t.position() - (Eigen::Vector2d(1, 1) + v * 4.0)).norm(), 0.08);
  EXPECT_NEAR(t.age(), 4.0, 1e-9);
  EXPECT_NEAR(t.stamp, 4.0, 1e-12);
  EXPECT_GT(t.confidence, 0.9);
  EXPECT_NEAR(t.leg_separation, 0.25, 1e-9);
  EXPECT_LT(t.positionCovariance().trace(), 2 * 0.05 * 0.05);
}

class CrossingTest : public ::testing::TestWithParam<Association> {};

TEST_P(CrossingTest, NoIdentitySwapWhenTwoPeopleCross) {
  TrackerParams p;
  p.association = GetParam();
  PeopleTracker tracker(p);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 0.04);
  // A walks (-3,-0.8) -> (3,0.8), B walks (-3,0.8) -> (3,-0.8); they meet at the origin at t = 2.5 s.
  auto a = [](double t) { return Eigen::Vector2d(-3 + 1.2 * t, -0.8 + 0.32 * t); };
  auto b = [](double t) { return Eigen::Vector2d(-3 + 1.2 * t, 0.8 - 0.32 * t); };
  int id_a = -1, id_b = -1;
  for (int k = 0; k <= 50; ++k) {
    const double t = 0.1 * k;
    std::vector<PersonDetection> d{det(a(t) + Eigen::Vector2d(n(rng), n(rng))), det(b(t) + Eigen::Vector2d(n(rng), n(rng)))};
    if (k % 2) std::swap(d[0], d[1]);  // detection order carries no identity
    tracker.updateInFrame(t, d);
    if (k == 10) {
      const auto c = tracker.confirmedTracks();
      ASSERT_EQ(c.size(), 2u);
      id_a = nearest(c, a(t))->id;
      id_b = nearest(c, b(t))->id;
      ASSERT_NE(id_a, id_b);
    }
  }
  const auto c = tracker.confirmedTracks();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(nearest(c, a(5.0))->id, id_a);
  EXPECT_EQ(nearest(c, b(5.0))->id, id_b);
  EXPECT_LT((nearest(c, a(5.0))->position() - a(5.0)).norm(), 0.1);
}

INSTANTIATE_TEST_SUITE_P(Association, CrossingTest, ::testing::Values(Association::kGnn, Association::kJpda),
                         [](const auto& info) { return std::string(toString(info.param)); });

TEST(Tracker, RobotMotionIsCompensated) {
  // A person stands at (3, 1) in odom while the robot drives and turns; detections come in the sensor frame.
  PeopleTracker tracker;
  const Eigen::Vector2d person(3.0, 1.0);
  for (int k = 0; k <= 30; ++k) {
    const double t = 0.1 * k;
    const Pose2 robot{0.5 * t, 0.1 * t, 0.3 * t};
    tracker.update(t, {det(robot.inverseTransform(person), 0.03)}, robot);
  }
  const auto c = tracker.confirmedTracks();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_LT((c[0].position() - person).norm(), 0.02);
  EXPECT_LT(c[0].velocity().norm(), 0.05);
  // The covariance is rotated into the tracking frame as well: an elongated sensor-frame covariance.
  PeopleTracker t2;
  PersonDetection d = det({2, 0});
  d.covariance << 0.04, 0, 0, 0.0001;
  t2.update(0.0, {d}, Pose2{0, 0, M_PI / 2});
  EXPECT_NEAR(t2.tracks()[0].positionCovariance()(1, 1), 0.04, 1e-12);
  EXPECT_NEAR(t2.tracks()[0].position().y(), 2.0, 1e-12);
}

TEST(Tracker, InitiationConfirmationDeletion) {
  TrackerParams p;
  PeopleTracker tracker(p);
  tracker.updateInFrame(0.0, {det({5, 5})});  // one-off clutter
  EXPECT_EQ(tracker.tracks().size(), 1u);
  EXPECT_FALSE(tracker.tracks()[0].confirmed);
  for (int k = 1; k <= 10; ++k) tracker.updateInFrame(0.1 * k, {det({1, 0})});
  // Clutter track was deleted after tentative_timeout; the person is confirmed.
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_TRUE(tracker.tracks()[0].confirmed);
  const int id = tracker.tracks()[0].id;
  // The person disappears: the confirmed track coasts, then is deleted after delete_timeout.
  ASSERT_DOUBLE_EQ(p.delete_timeout, 1.5);
  for (int k = 1; k <= 14; ++k) tracker.updateInFrame(1.0 + 0.1 * k, {});  // 1.4 s without detections
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].id, id);
  EXPECT_LT(tracker.tracks()[0].confidence, 0.2);
  tracker.updateInFrame(2.6, {});  // 1.6 s
  EXPECT_TRUE(tracker.tracks().empty());
}

TEST(Tracker, ResetsCleanlyOnTimeJumps) {
  PeopleTracker tracker;
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(tracker.updateInFrame(10.0 + 0.1 * k, {det({1, 0})}).reset);
  ASSERT_EQ(tracker.confirmedTracks().size(), 1u);
  const TrackerStatus back = tracker.updateInFrame(9.0, {det({2, 0})});  // bag loop: time goes backwards
  EXPECT_TRUE(back.reset);
  EXPECT_NE(back.reason.find("backwards"), std::string::npos);
  ASSERT_EQ(tracker.tracks().size(), 1u);  // restarted from the current detections
  EXPECT_FALSE(tracker.tracks()[0].confirmed);
  EXPECT_TRUE(tracker.tracks()[0].position().isApprox(Eigen::Vector2d(2, 0)));
  const TrackerStatus jump = tracker.updateInFrame(100.0, {});
  EXPECT_TRUE(jump.reset);
  EXPECT_TRUE(tracker.tracks().empty());
  EXPECT_THROW(tracker.updateInFrame(std::nan(""), {}), InputError);
  EXPECT_THROW(associationFromString("mht"), InputError);
}

TEST(Tracker, IgnoresNonFiniteDetections) {
  PeopleTracker tracker;
  PersonDetection bad = det({1, 1});
  bad.position.x() = std::nan("");
  tracker.updateInFrame(0.0, {bad, det({2, 2})});
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_TRUE(tracker.tracks()[0].position().allFinite());
}
