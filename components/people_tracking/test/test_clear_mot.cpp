#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "cairn/people_tracking/clear_mot.hpp"
#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/trajectories.hpp"

using namespace cairn::people_tracking;

TEST(ClearMot, CountsMatchesMissesFalsePositivesAndSwitches) {
  ClearMot mot(0.5);
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{10, {0.1, 0}}, {20, {5, 0.2}}});  // 2 matches
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{10, {0.1, 0}}, {30, {9, 9}}});   // FN for 2, FP for 30
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{11, {0.0, 0}}, {20, {5, 0}}});   // 1 switches 10 -> 11
  mot.addFrame({{1, {0, 0}}}, {{11, {0.0, 0.3}}, {40, {3, 3}}}, {{3, 3.2}});  // 40 is next to a don't-care person
  const MotMetrics m = mot.metrics();
  EXPECT_EQ(m.frames, 4u);
  EXPECT_EQ(m.gt, 7u);
  EXPECT_EQ(m.matches, 6u);
  EXPECT_EQ(m.fn, 1u);
  EXPECT_EQ(m.fp, 1u);
  EXPECT_EQ(m.ignored, 1u);
  EXPECT_EQ(m.id_switches, 1u);
  EXPECT_EQ(m.gt_tracks, 2u);
  EXPECT_NEAR(m.mota(), 1.0 - 3.0 / 7.0, 1e-12);
  EXPECT_NEAR(m.motp(), (0.1 + 0.2 + 0.1 + 0 + 0 + 0.3) / 6.0, 1e-12);
  EXPECT_NEAR(m.idSwitchesPer100Tracks(), 50.0, 1e-12);
}

TEST(ClearMot, LastFrameListsCorrespondencesAndTheSwitchedFromTrack) {
  ClearMot mot(0.5);
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{10, {0.1, 0}}, {20, {5, 0.2}}});
  ASSERT_EQ(mot.lastFrame().size(), 2u);
  for (const auto& c : mot.lastFrame()) EXPECT_EQ(c.switched_from, -1);
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{10, {0.1, 0}}});  // 2 unmatched: only 1 listed
  ASSERT_EQ(mot.lastFrame().size(), 1u);
  EXPECT_EQ(mot.lastFrame()[0].gt, 1);
  mot.addFrame({{1, {0, 0}}, {2, {5, 0}}}, {{11, {0.0, 0}}, {20, {5, 0}}});  // 1: 10 -> 11, 2 keeps 20 after a gap
  ASSERT_EQ(mot.lastFrame().size(), 2u);
  for (const auto& c : mot.lastFrame()) {
    if (c.gt == 1) {
      EXPECT_EQ(c.hyp, 11);
      EXPECT_EQ(c.switched_from, 10);
    } else {
      EXPECT_EQ(c.hyp, 20);
      EXPECT_EQ(c.switched_from, -1);
    }
  }
  EXPECT_EQ(mot.metrics().id_switches, 1u);
}

TEST(ClearMot, KeepsCorrespondenceOverACloserHypothesis) {
  // Once 1<->10 is established it is kept while within the threshold even if 11 is closer: no switch.
  ClearMot mot(0.5);
  mot.addFrame({{1, {0, 0}}}, {{10, {0.0, 0}}});
  mot.addFrame({{1, {0, 0}}}, {{10, {0.4, 0}}, {11, {0.05, 0}}});
  const MotMetrics m = mot.metrics();
  EXPECT_EQ(m.id_switches, 0u);
  EXPECT_EQ(m.fp, 1u);
  EXPECT_NEAR(m.motp(), 0.2, 1e-12);
}

TEST(ClearMot, HypothesisOnADontCarePersonIsNotMatchedToACountedNeighbour) {
  // Person 1 counts; a second person 0.6 m away does not (out of range or sight) and is tracked by 20, which is
  // also within 0.5 m of person 1. As in MOTChallenge's distractor preprocessing, 20 goes to the don't-care
  // person (ignored), so person 1 is a miss until its own track 10 appears, and then no ID switch.
  ClearMot mot(0.5);
  mot.addFrame({{1, {0, 0}}}, {{20, {0.4, 0}}}, {{0.6, 0}});
  mot.addFrame({{1, {0, 0}}}, {{20, {0.4, 0}}, {10, {0.05, 0}}}, {{0.6, 0}});
  const MotMetrics m = mot.metrics();
  EXPECT_EQ(m.fn, 1u);
  EXPECT_EQ(m.matches, 1u);
  EXPECT_EQ(m.ignored, 2u);
  EXPECT_EQ(m.fp, 0u);
  EXPECT_EQ(m.id_switches, 0u);
  // Two hypotheses on one don't-care person: one is ignored, the other is a false positive.
  ClearMot two(0.5);
  two.addFrame({}, {{30, {5, 5}}, {31, {5.1, 5}}}, {{5.05, 5}});
  EXPECT_EQ(two.metrics().ignored, 1u);
  EXPECT_EQ(two.metrics().fp, 1u);
}

namespace {
std::string data(const std::string& f) { return std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/" + f; }
}  // namespace

TEST(Trajectories, LoadsEthObsmat) {
  const TrajectorySet s = loadTrajectories(data("eth_seq_eth_obsmat_head400.txt"));
  EXPECT_EQ(s.format, "obsmat");
  EXPECT_EQ(s.samples(), 400u);
  EXPECT_EQ(s.people.size(), 20u);
  // First row: frame 780, id 1, x 8.4568443, y 3.5880664; frames step 6 = 0.4 s.
  EXPECT_NEAR(s.t_begin, 780.0 / 6.0 * 0.4, 1e-9);
  const auto p = s.positionAt(1, s.t_begin);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x(), 8.4568443, 1e-9);
  EXPECT_NEAR(p->y(), 3.5880664, 1e-9);
  const auto mid = s.positionAt(1, s.t_begin + 0.2);  // halfway to the second row (9.1255301, 3.6585832)
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->x(), 0.5 * (8.4568443 + 9.1255301), 1e-9);
  EXPECT_FALSE(s.positionAt(1, s.t_begin - 0.1).has_value());
  EXPECT_FALSE(s.positionAt(12345, s.t_begin).has_value());
}

TEST(Trajectories, LoadsEdinburghTracks) {
  const TrajectorySet s = loadTrajectories(data("edinburgh_tracks_01Aug_head12.txt"));
  EXPECT_EQ(s.format, "edinburgh");
  EXPECT_EQ(s.people.size(), 5u);
  const auto& r1 = s.people.at(1);
  EXPECT_NEAR(r1.front().p.x(), 601 * 0.0247, 1e-12);  // [601 23 4471]
  EXPECT_NEAR(r1.front().p.y(), 23 * 0.0247, 1e-12);
  EXPECT_NEAR(r1.front().t, 4471 / 9.0, 1e-12);
}

TEST(Trajectories, LoadsCsvAndRejectsBadInput) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string csv = (dir / ("cairn_pt_traj_" + std::to_string(::getpid()) + ".csv")).string();
  std::ofstream(csv) << "t,id,x,y\n0.0,3,1.0,2.0\n1.0,3,2.0,2.0\n0.5,4,0,0\n";
  const TrajectorySet s = loadTrajectories(csv);
  EXPECT_EQ(s.format, "csv");
  EXPECT_EQ(s.people.size(), 2u);
  EXPECT_NEAR(s.positionAt(3, 0.25)->x(), 1.25, 1e-12);
  std::ofstream(csv) << "t,id,x,y\n0.0,3,1.0\n";
  EXPECT_THROW(loadTrajectories(csv), InputError);
  std::ofstream(csv) << "1 2 abc\n";
  EXPECT_THROW(loadTrajectories(csv), InputError);
  std::filesystem::remove(csv);
  EXPECT_THROW(loadTrajectories("/nonexistent/file.txt"), InputError);
}

// Local linear smoothing: constant-velocity motion (also its ends) stays exactly where it was, alternating
// annotation jitter shrinks, and a gap splits a person's track into separately smoothed pieces.
TEST(Trajectories, SmoothingKeepsStraightLinesAndRemovesJitter) {
  TrajectorySet s;
  s.max_gap = 1.0;
  std::vector<TrajectoryPoint>& line = s.people[1];
  std::vector<TrajectoryPoint>& noisy = s.people[2];
  std::vector<TrajectoryPoint>& gapped = s.people[3];
  for (int k = 0; k < 20; ++k) {
    const double t = 0.4 * k;
    line.push_back({t, Eigen::Vector2d(1.3 * t, 2.0 - 0.4 * t)});
    noisy.push_back({t, Eigen::Vector2d(1.3 * t, (k % 2 ? 0.05 : -0.05))});  // +-5 cm zig-zag across the walk
  }
  for (int k = 0; k < 5; ++k) gapped.push_back({0.4 * k, Eigen::Vector2d(0.0, 0.0)});
  for (int k = 0; k < 5; ++k) gapped.push_back({10.0 + 0.4 * k, Eigen::Vector2d(5.0, 0.0)});  // 8.4 s gap
  const TrajectorySet raw = s;
  smoothTrajectories(s, 0.4);
  for (std::size_t k = 0; k < line.size(); ++k) {
    EXPECT_NEAR(line[k].p.x(), raw.people.at(1)[k].p.x(), 1e-9);
    EXPECT_NEAR(line[k].p.y(), raw.people.at(1)[k].p.y(), 1e-9);
    EXPECT_EQ(line[k].t, raw.people.at(1)[k].t);
  }
  for (std::size_t k = 2; k + 2 < noisy.size(); ++k) {
    EXPECT_NEAR(noisy[k].p.x(), raw.people.at(2)[k].p.x(), 1e-9);  // the walk itself is a line
    EXPECT_LT(std::abs(noisy[k].p.y()), 0.025);                      // jitter at least halved
  }
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(gapped[static_cast<std::size_t>(k)].p.x(), 0.0, 1e-12);  // not pulled across
  for (int k = 5; k < 10; ++k) EXPECT_NEAR(gapped[static_cast<std::size_t>(k)].p.x(), 5.0, 1e-12);
  EXPECT_EQ(s.min, raw.min);  // bounds stay those of the annotations
  EXPECT_THROW(smoothTrajectories(s, 0.0), InputError);
  EXPECT_THROW(smoothTrajectories(s, -1.0), InputError);
  EXPECT_THROW(smoothTrajectories(s, std::nan("")), InputError);
}
