#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "cairn/people_tracking/clear_mot.hpp"
#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/track_metrics.hpp"
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
  EXPECT_EQ(m.id_transfers, 0u);  // 11 and 20 each stayed on one person
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

TEST(Trajectories, LoadsLongEdinburghTracksAndRejectsMalformedEntries) {
  // The shipped tracks.01Aug.txt has a track of 82 kB on one line; a regex-based parser overflowed the stack on it
  // (segfault). 20 000 points here, then malformed entries: each one line naming file:line, no crash.
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / ("cairn_pt_edinburgh_" + std::to_string(::getpid()) + ".txt")).string();
  {
    std::ofstream f(path);
    f << "% Total number of trajectories in file are  1\n\nProperties.R3=[20000 0 19999];\n TRACK.R3=[";
    for (int k = 0; k < 20000; ++k) f << (k ? ";" : "") << "[" << 100 + k % 50 << " " << 200 << " " << k << "]";
    f << "];\n";
  }
  const TrajectorySet s = loadTrajectories(path);
  EXPECT_EQ(s.format, "edinburgh");
  ASSERT_EQ(s.people.at(3).size(), 20000u);
  EXPECT_NEAR(s.people.at(3).back().t, 19999 / 9.0, 1e-9);
  for (const std::string bad : {"TRACK.Rx=[[1 2 3]];", "TRACK.R4 [[1 2 3]];", "TRACK.R4=[[1 2 3];", "TRACK.R4=[[1 2 3]]; junk",
                                 "TRACK.R4=[[1 2 abc]];", "TRACK.R99999999999=[[1 2 3]];"}) {
    std::ofstream(path) << "TRACK.R1=[[1 2 3];[2 2 4]];\n" << bad << "\n";
    try {
      (void)loadTrajectories(path);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":2: "), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(path);
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

// Id exchanges in a recording (fixIdExchanges): two people walk side by side 0.6 m apart at 1.3 m/s; the
// annotator exchanged their ids after t = 2.0 s, so as recorded each jumps 0.6 m sideways within one 0.4 s period.
// The exchange is found and undone (both paths straight again); a constant-velocity crossing of two others, a pair
// walking together and one person turning sharply stay as they are.
TEST(Trajectories, IdExchangesAreFoundAndUndone) {
  TrajectorySet s;
  s.max_gap = 1.0;
  for (int k = 0; k < 12; ++k) {
    const double t = 0.4 * k;
    const bool swapped = t > 2.0 + 1e-9;
    s.people[1].push_back({t, Eigen::Vector2d(1.3 * t, swapped ? 0.6 : 0.0)});
    s.people[2].push_back({t, Eigen::Vector2d(1.3 * t, swapped ? 0.0 : 0.6)});
    s.people[3].push_back({t, Eigen::Vector2d(10.0 + 1.3 * t, 5.0)});         // 3 and 4 cross at right angles,
    s.people[4].push_back({t, Eigen::Vector2d(10.0 + 2.6, 2.4 + 1.3 * t)});   // both at (12.6, 5) at t = 2.0
    s.people[5].push_back({t, Eigen::Vector2d(-10.0 + 1.3 * t, -5.0)});       // 5 and 6 walk together
    s.people[6].push_back({t, Eigen::Vector2d(-10.0 + 1.3 * t, -5.6)});
    // 7 turns by 90 degrees at t = 2.0 next to nobody
    s.people[7].push_back({t, t <= 2.0 ? Eigen::Vector2d(20.0 + 1.3 * t, 20.0) : Eigen::Vector2d(22.6, 20.0 + 1.3 * (t - 2.0))});
  }
  const TrajectorySet raw = s;
  const std::vector<IdExchange> fixed = fixIdExchanges(s);
  ASSERT_EQ(fixed.size(), 1u);
  EXPECT_EQ(std::min(fixed[0].a, fixed[0].b), 1);
  EXPECT_EQ(std::max(fixed[0].a, fixed[0].b), 2);
  EXPECT_DOUBLE_EQ(fixed[0].after, 2.0);
  for (int k = 0; k < 12; ++k) {
    EXPECT_NEAR(s.people.at(1)[static_cast<std::size_t>(k)].p.y(), 0.0, 1e-12);
    EXPECT_NEAR(s.people.at(2)[static_cast<std::size_t>(k)].p.y(), 0.6, 1e-12);
  }
  for (int id = 3; id <= 7; ++id) {
    ASSERT_EQ(s.people.at(id).size(), raw.people.at(id).size());
    for (std::size_t k = 0; k < s.people.at(id).size(); ++k) EXPECT_EQ(s.people.at(id)[k].p, raw.people.at(id)[k].p);
  }
  EXPECT_EQ(s.samples(), raw.samples());
  EXPECT_EQ(s.min, raw.min);
  EXPECT_TRUE(fixIdExchanges(s).empty());  // nothing left to undo
  IdExchangeParams bad;
  bad.ratio = 1.5;
  EXPECT_THROW(fixIdExchanges(s, bad), InputError);
}

// HOTA and OSPA (track_metrics.hpp) on scripted sequences whose values follow from the definitions by hand.
namespace {
Hota scoreHota(const std::vector<std::pair<std::vector<MotObject>, std::vector<MotObject>>>& frames) {
  Hota h(1.0, 0.5);
  for (const auto& [gt, hyp] : frames) h.addFrame(gt, hyp);
  return h;
}
}  // namespace

TEST(Hota, PerfectTrackingScoresOneAndOspaZero) {
  std::vector<std::pair<std::vector<MotObject>, std::vector<MotObject>>> frames;
  Ospa ospa;
  for (int t = 0; t < 10; ++t) {
    frames.push_back({{{1, {0.1 * t, 0}}, {2, {3, 0.1 * t}}}, {{7, {0.1 * t, 0}}, {9, {3, 0.1 * t}}}});
    ospa.addFrame(frames.back().first, frames.back().second);
  }
  const HotaMetrics m = scoreHota(frames).metrics();
  EXPECT_NEAR(m.hota, 1.0, 1e-12);
  EXPECT_NEAR(m.deta, 1.0, 1e-12);
  EXPECT_NEAR(m.assa, 1.0, 1e-12);
  EXPECT_NEAR(m.loca, 1.0, 1e-12);
  EXPECT_NEAR(ospa.mean(), 0.0, 1e-12);
}

TEST(Hota, AnIdSwitchCostsAssociationInProportionToWhatItConfuses) {
  // One person, 10 frames, tracked exactly; the track id changes after frame 5 (halfway) or after frame 1.
  auto run = [](int switch_at) {
    std::vector<std::pair<std::vector<MotObject>, std::vector<MotObject>>> frames;
    for (int t = 0; t < 10; ++t) frames.push_back({{{1, {0.2 * t, 0}}}, {{t < switch_at ? 10 : 11, {0.2 * t, 0}}}});
    return scoreHota(frames).metrics();
  };
  const HotaMetrics half = run(5), early = run(1);
  // Halfway: each pair is matched 5 of the person's 10 frames and of the track's 5: Ass-IoU 5 / (10 + 5 - 5).
  EXPECT_NEAR(half.deta, 1.0, 1e-12);
  EXPECT_NEAR(half.assa, 0.5, 1e-12);
  EXPECT_NEAR(half.hota, std::sqrt(0.5), 1e-12);
  // After the first frame: one match at Ass-IoU 1/10, nine at 9/10.
  EXPECT_NEAR(early.assa, (1 * 0.1 + 9 * 0.9) / 10, 1e-12);
  EXPECT_NEAR(early.hota, std::sqrt(0.82), 1e-12);
  // CLEAR MOT counts one switch either way.
  for (int at : {1, 5}) {
    ClearMot mot(0.5);
    for (int t = 0; t < 10; ++t) mot.addFrame({{1, {0.2 * t, 0}}}, {{t < at ? 10 : 11, {0.2 * t, 0}}});
    EXPECT_EQ(mot.metrics().id_switches, 1u);
  }
}

TEST(Hota, MissesLowerDetectionAndAssociationLocalisationErrorLowersTheHighThresholds) {
  std::vector<std::pair<std::vector<MotObject>, std::vector<MotObject>>> missed, offset;
  Ospa ospa;
  for (int t = 0; t < 10; ++t) {
    missed.push_back({{{1, {0, 0.3 * t}}}, {}});
    if (t < 5) missed.back().second.push_back({4, {0, 0.3 * t}});
    offset.push_back({{{1, {0, 0.3 * t}}}, {{4, {0.25, 0.3 * t}}}});
    ospa.addFrame(offset.back().first, offset.back().second);
  }
  // Tracked in 5 of 10 frames: DetA 5 / (10 + 5 - 5); the person's 5 unmatched frames are FNA: AssA 5 / 10.
  const HotaMetrics m = scoreHota(missed).metrics();
  EXPECT_NEAR(m.deta, 0.5, 1e-12);
  EXPECT_NEAR(m.assa, 0.5, 1e-12);
  EXPECT_NEAR(m.hota, 0.5, 1e-12);
  // 0.25 m off with zero_distance 1 m: S = 0.75, a match at alpha 0.05 ... 0.75 (15 of 19) and none above.
  const HotaMetrics o = scoreHota(offset).metrics();
  EXPECT_NEAR(o.hota, 15.0 / 19.0, 1e-12);
  EXPECT_NEAR(o.hota_alpha[14], 1.0, 1e-12);
  EXPECT_NEAR(o.hota_alpha[15], 0.0, 1e-12);
  EXPECT_NEAR(o.loca, 0.75, 1e-12);  // over the thresholds with matches
  EXPECT_NEAR(ospa.mean(), 0.25, 1e-12);
}

TEST(Hota, MatchingPrefersThePairThatIsAlignedOverTheWholeSequence) {
  // Track 10 follows person 1 in all 10 frames; in frame 5 it is 0.2 m off and a one-frame hypothesis 11 sits
  // 0.05 m from the person. Matching by distance alone would give that frame to 11; A_max(1, 10) = 1 vs
  // A_max(1, 11) = 0.1 keeps 10, so association stays perfect up to alpha 0.8 (S = 0.8 for 10 in frame 5).
  std::vector<std::pair<std::vector<MotObject>, std::vector<MotObject>>> frames;
  for (int t = 0; t < 10; ++t) {
    frames.push_back({{{1, {0.3 * t, 0}}}, {{10, {0.3 * t, t == 5 ? 0.2 : 0.0}}}});
    if (t == 5) frames.back().second.push_back({11, {0.3 * t, 0.05}});
  }
  const HotaMetrics m = scoreHota(frames).metrics();
  for (int k = 0; k < 16; ++k) EXPECT_NEAR(m.assa_alpha[static_cast<std::size_t>(k)], 1.0, 1e-12) << "alpha " << HotaMetrics::alpha(k);
  EXPECT_NEAR(m.deta_alpha[0], 10.0 / 11.0, 1e-12);  // 11 is a false positive
}

TEST(Hota, DontCareRuleAndOspaCardinality) {
  // A hypothesis on a person who does not count is neither matched nor false: perfect scores.
  Hota h(1.0, 0.5);
  Ospa ospa(1.0, 1.0, 0.5);
  for (int t = 0; t < 4; ++t) {
    h.addFrame({{1, {0, 0}}}, {{10, {0, 0}}, {20, {5, 0.1}}}, {{5, 0}});
    ospa.addFrame({{1, {0, 0}}}, {{10, {0, 0}}, {20, {5, 0.1}}}, {{5, 0}});
  }
  EXPECT_NEAR(h.metrics().hota, 1.0, 1e-12);
  EXPECT_NEAR(ospa.mean(), 0.0, 1e-12);
  // Two people, one hypothesis exactly on one of them: (0 + c) / 2 with c = 1 m.
  Ospa card(1.0, 1.0);
  card.addFrame({{1, {0, 0}}, {2, {3, 0}}}, {{10, {0, 0}}});
  EXPECT_NEAR(card.last(), 0.5, 1e-12);
  card.addFrame({}, {});  // nothing present: not averaged
  EXPECT_NEAR(card.mean(), 0.5, 1e-12);
  // Order 2: sqrt((0.6^2 + 0^2) / 2) for two matched pairs.
  Ospa two(1.0, 2.0);
  two.addFrame({{1, {0, 0}}, {2, {3, 0}}}, {{10, {0.6, 0}}, {11, {3, 0}}});
  EXPECT_NEAR(two.last(), std::sqrt(0.18), 1e-12);
}

TEST(IdF1, ChargesATrackThatCarriesOneIdOverTwoPeopleWhichClearMotDoesNotCount) {
  // Person 1 walks for 10 frames and leaves; person 2 appears and walks 10 frames. One track (id 5) follows
  // person 1 and then person 2. CLEAR MOT counts no switch (person 2 is matched for the first time); IDF1 assigns
  // track 5 to one of them: IDTP 10 of 20 + 20 frames.
  ClearMot mot(0.5);
  IdF1 idf1(0.5);
  Hota hota(1.0, 0.5);
  for (int t = 0; t < 20; ++t) {
    const std::vector<MotObject> gt{{t < 10 ? 1 : 2, {0.1 * t, 0}}};
    const std::vector<MotObject> hyp{{5, {0.1 * t, 0}}};
    mot.addFrame(gt, hyp);
    idf1.addFrame(gt, hyp);
    hota.addFrame(gt, hyp);
  }
  EXPECT_EQ(mot.metrics().id_switches, 0u);
  EXPECT_EQ(mot.metrics().id_transfers, 1u);  // track 5: person 1, then person 2
  EXPECT_NEAR(mot.metrics().mota(), 1.0, 1e-12);
  const IdF1::Result r = idf1.metrics();
  EXPECT_EQ(r.idtp, 10u);
  EXPECT_NEAR(r.idf1, 0.5, 1e-12);
  EXPECT_NEAR(r.idp, 0.5, 1e-12);
  EXPECT_NEAR(r.idr, 0.5, 1e-12);
  EXPECT_NEAR(hota.metrics().assa, 0.5, 1e-12);  // each pair: 10 / (10 + 20 - 10)
}

TEST(IdF1, AssignmentMaximisesFramesNotPairs) {
  // Person 1 is tracked by 10 for 10 frames; in the first frame 11 is within 0.5 m of person 1 (not of person 2)
  // and person 2 within 0.5 m of 10. Maximising the number of assigned pairs would give 1-11 and 2-10 (2 frames);
  // IDTP must be 10 (1-10).
  IdF1 idf1(0.5);
  for (int t = 0; t < 10; ++t) {
    std::vector<MotObject> gt{{1, {0, 0}}}, hyp{{10, {0, 0}}};
    if (t == 0) {
      gt.push_back({2, {0.45, 0}});
      hyp.push_back({11, {-0.1, -0.4}});
    }
    idf1.addFrame(gt, hyp);
  }
  EXPECT_EQ(idf1.metrics().idtp, 10u);
}
