#include <gtest/gtest.h>

#include "cairn/people_tracking/guide.hpp"

using namespace cairn::people_tracking;

namespace {
Track track(int id, double x, double y, double last_update, bool confirmed = true) {
  Track t;
  t.id = id;
  t.state << x, y, 0, 0;
  t.stamp = last_update;
  t.last_update = last_update;
  t.confirmed = confirmed;
  return t;
}
}  // namespace

TEST(Guide, SelectsClosestPersonInFront) {
  GuideTracker g;
  const Pose2 robot{};
  const std::vector<Track> tracks{track(1, -1.0, 0.0, 0), track(2, 2.0, 0.5, 0), track(3, 1.5, -0.2, 0),
                                  track(4, 0.8, 0.1, 0, false)};
  EXPECT_EQ(g.update(tracks, robot, 0).state, GuideState::kSearch);
  ASSERT_TRUE(g.selectClosestInFront(tracks, robot, 0.0));  // 1 is behind, 4 is tentative
  const GuideStatus s = g.update(tracks, robot, 0.0);
  EXPECT_EQ(s.state, GuideState::kTracking);
  EXPECT_EQ(s.guide_id, 3);
  EXPECT_EQ(s.event, "selected");
  EXPECT_NEAR(s.distance, std::hypot(1.5, 0.2), 1e-12);
  EXPECT_NEAR(s.bearing, std::atan2(-0.2, 1.5), 1e-12);
  ASSERT_TRUE(s.track.has_value());
  // Nobody in front within select_max_distance: select fails and keeps the state.
  GuideTracker h;
  EXPECT_FALSE(h.selectClosestInFront({track(1, -1.0, 0.0, 0), track(2, 5.0, 0.0, 0)}, robot, 0.0));
  EXPECT_EQ(h.state(), GuideState::kSearch);
}

TEST(Guide, LostWhenLeavingTheFieldThenReacquired) {
  GuideTracker g;
  Pose2 robot{};
  ASSERT_TRUE(g.selectId(5, {track(5, 2.0, 0.0, 0)}, 0.0));
  EXPECT_EQ(g.update({track(5, 7.9, 0.0, 1.0)}, robot, 1.0).state, GuideState::kTracking);
  const GuideStatus lost = g.update({track(5, 8.2, 0.0, 1.1)}, robot, 1.1);  // beyond the 8 m field
  EXPECT_EQ(lost.state, GuideState::kPersonLost);
  EXPECT_EQ(lost.event, "lost: left field");
  EXPECT_FALSE(lost.track.has_value());
  robot.x = 1.0;  // the robot catches up: the same track is back inside the field
  const GuideStatus back = g.update({track(5, 8.3, 0.0, 1.2)}, robot, 1.2);
  EXPECT_EQ(back.state, GuideState::kTracking);
  EXPECT_EQ(back.event, "reacquired");
  // Behind the robot is outside the semicircle.
  EXPECT_EQ(g.update({track(5, 0.5, 0.0, 1.3)}, robot, 1.3).event, "lost: left field");
}

TEST(Guide, LostOnTimeoutAndReacquiredByANewTrackNearby) {
  GuideParams p;
  GuideTracker g(p);
  const Pose2 robot{};
  ASSERT_TRUE(g.selectId(1, {track(1, 2.0, 0.0, 0.0)}, 0.0));
  g.update({track(1, 2.0, 0.0, 0.0)}, robot, 0.0);
  // Track still exists (coasting) but unmatched for longer than lost_timeout.
  const GuideStatus s = g.update({track(1, 2.0, 0.0, 0.0)}, robot, p.lost_timeout + 0.1);
  EXPECT_EQ(s.state, GuideState::kPersonLost);
  EXPECT_EQ(s.event, "lost: timeout");
  // A fresh track 3 m away does not qualify; one 0.5 m from the last guide position does.
  EXPECT_EQ(g.update({track(7, 5.0, 0.0, 1.5)}, robot, 1.5).state, GuideState::kPersonLost);
  const GuideStatus r = g.update({track(7, 5.0, 0.0, 1.6), track(8, 2.4, 0.3, 1.6)}, robot, 1.6);
  EXPECT_EQ(r.state, GuideState::kTracking);
  EXPECT_EQ(r.guide_id, 8);
}

TEST(Guide, TrackDeletionAndGivingUp) {
  GuideParams p;
  p.auto_reacquire = false;
  GuideTracker g(p);
  const Pose2 robot{};
  ASSERT_TRUE(g.selectId(1, {track(1, 2.0, 0.0, 0.0)}, 0.0));
  EXPECT_EQ(g.update({}, robot, 0.1).event, "lost: track deleted");
  EXPECT_EQ(g.update({track(2, 2.0, 0.0, 0.2)}, robot, 0.2).state, GuideState::kPersonLost);  // no auto reacquire
  const GuideStatus s = g.update({}, robot, 0.1 + p.reacquire_window + 0.1);
  EXPECT_EQ(s.state, GuideState::kSearch);
  EXPECT_EQ(s.event, "gave up");
  EXPECT_EQ(s.guide_id, -1);
  EXPECT_FALSE(g.selectId(9, {track(9, 1, 0, 0, false)}, 0.0));  // tentative tracks cannot be selected
}
