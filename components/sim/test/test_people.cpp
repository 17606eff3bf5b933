#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "cairn/sim/people.hpp"

using namespace cairn::sim;
constexpr double kPi = std::numbers::pi;
const std::string kPeopleData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/";

TEST(Legs, GeometryFollowsGait) {
  const GaitConfig g;
  Vec2 legs[2];
  // standing: legs side by side, hip_half_width left/right of the heading (here +y)
  legPositions(g, {1, 1}, kPi / 2, 0.0, 1.0, legs);
  EXPECT_NEAR(legs[0].x, 1 - g.hip_half_width, 1e-12);
  EXPECT_NEAR(legs[1].x, 1 + g.hip_half_width, 1e-12);
  EXPECT_NEAR(legs[0].y, 1.0, 1e-12);
  // walking at full swing speed, phase pi/2: left leg forward by the amplitude, right leg back
  legPositions(g, {0, 0}, 0.0, 1.2, kPi / 2, legs);
  EXPECT_NEAR(legs[0].x, g.swing_amplitude, 1e-12);
  EXPECT_NEAR(legs[1].x, -g.swing_amplitude, 1e-12);
  EXPECT_NEAR(norm(legs[0] - legs[1]), 2 * std::hypot(g.hip_half_width, g.swing_amplitude), 1e-12);
  // half speed: half amplitude; the midpoint of the legs is always the person's position
  legPositions(g, {3, -2}, 0.7, 0.5, 0.3, legs);
  EXPECT_NEAR(0.5 * (legs[0].x + legs[1].x), 3.0, 1e-12);
  EXPECT_NEAR(0.5 * (legs[0].y + legs[1].y), -2.0, 1e-12);
}

TEST(Trajectories, CsvFormatAndErrors) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_people";
  fs::create_directories(dir);
  {
    std::ofstream f(dir / "ok.csv");
    f << "t,id,x,y\n# comment\n0.0,7,1.0,2.0\n1.0,7,2.0,2.0\n0.5,3,0,0\n2.0,7,2.0,4.0\n";
  }
  const auto trajs = loadTrajectoriesCsv((dir / "ok.csv").string());
  ASSERT_EQ(trajs.size(), 2u);
  EXPECT_EQ(trajs[1].id, 7);
  ASSERT_EQ(trajs[1].t.size(), 3u);
  Vec2 p, v;
  trajs[1].sample(1.5, p, v);
  EXPECT_NEAR(p.x, 2.0, 1e-12);
  EXPECT_NEAR(p.y, 3.0, 1e-12);
  EXPECT_NEAR(v.y, 2.0, 1e-12);
  {
    std::ofstream f(dir / "bad.csv");
    f << "t,id,x,y\n0,1,0,0\n1,1,zero,0\n";
  }
  try {
    loadTrajectoriesCsv((dir / "bad.csv").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
  }
}

TEST(Trajectories, EthObsmatExcerpt) {
  const auto trajs = loadEthObsmat(kPeopleData + "eth_seq_eth_obsmat_head400.txt");
  EXPECT_EQ(trajs.size(), 20u);
  // first row: frame 780, ped 1, x 8.4568443, y 3.5880664; ETH annotations every 0.4 s (6 frames)
  const Trajectory& t1 = trajs.front();
  EXPECT_EQ(t1.id, 1);
  EXPECT_NEAR(t1.t.front(), 780 * 0.4 / 6, 1e-9);
  EXPECT_NEAR(t1.p.front().x, 8.4568443, 1e-9);
  EXPECT_NEAR(t1.p.front().y, 3.5880664, 1e-9);
  EXPECT_NEAR(t1.t[1] - t1.t[0], 0.4, 1e-9);
  // the recorded speed of pedestrian 1 at the first sample is (1.67, 0.18) m/s (obsmat v_x, v_y)
  Vec2 p, v;
  t1.sample(t1.t[0] + 0.2, p, v);
  EXPECT_NEAR(v.x, 1.67, 0.1);
}

TEST(Trajectories, EdinburghExcerpt) {
  const auto trajs = loadEdinburghTracks(kPeopleData + "edinburgh_tracks_01Aug_head12.txt");
  ASSERT_EQ(trajs.size(), 5u);
  // TRACK.R1 starts [601 23 4471]
  EXPECT_EQ(trajs[0].id, 1);
  EXPECT_NEAR(trajs[0].p.front().x, 601 * 0.0247, 1e-9);
  EXPECT_NEAR(trajs[0].t.front(), 4471 / 9.0, 1e-9);
  EXPECT_EQ(trajs[0].t.size(), 53u);  // Properties.R1: 53 points
}

TEST(Trajectories, EdinburghTruncatedOrWrongFilesAreErrors) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "cairn_sim_test_people_edinburgh";
  fs::create_directories(dir);
  auto errorOf = [&](const std::string& name, const std::string& text, const std::string& kind) -> std::string {
    std::ofstream(dir / name) << text;
    PeopleSource src;
    src.kind = kind;
    src.file = (dir / name).string();
    try {
      loadPeopleSource(src);
    } catch (const InputError& e) {
      return std::string(e.what()).substr(dir.string().size() + 1);
    }
    return "no error";
  };
  // a cut-off last line used to be read as the triples it had
  EXPECT_EQ(errorOf("cut.txt", " TRACK.R1=[[1 2 3];[4 5 6\n", "edinburgh"),
            "cut.txt:1: TRACK.R1: TRACK entries must be [x y t] triples (line cut off?)");
  EXPECT_EQ(errorOf("open.txt", " TRACK.R1=[[1 2 3];[4 5 6]\n", "edinburgh"),
            "open.txt:1: TRACK.R1: expected ';' or ']' after [x y t] (line cut off?)");
  EXPECT_EQ(errorOf("four.txt", " TRACK.R1=[[1 2 3 4]];\n", "edinburgh"),
            "four.txt:1: TRACK.R1: TRACK entries must be [x y t] triples");
  EXPECT_EQ(errorOf("ok.txt", " TRACK.R1=[[1 2 3];[4 5 6]];\n TRACK.R2=[[1 2 3]]\n", "edinburgh"), "no error");
  // the wrong kind for a file used to give no people and no error
  EXPECT_EQ(errorOf("walkers.csv", "t,id,x,y\n0,1,0,0\n", "edinburgh"),
            "walkers.csv:0: no trajectories (kind edinburgh: expected Edinburgh TRACK.R<id>=[[x y t];...] lines)");
  EXPECT_EQ(errorOf("empty.csv", "t,id,x,y\n", "csv"), "empty.csv:0: no trajectories (kind csv: expected t,id,x,y lines)");
  // a directory opened as an empty stream
  fs::create_directories(dir / "adir");
  for (const char* kind : {"csv", "eth_obsmat", "edinburgh"}) {
    PeopleSource src;
    src.kind = kind;
    src.file = (dir / "adir").string();
    try {
      loadPeopleSource(src);
      ADD_FAILURE() << kind << ": no error for a directory";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), src.file + ":0: is a directory, not a file");
    }
  }
}

TEST(Trajectories, TransformOffsetScale) {
  std::vector<Trajectory> t{{1, {0.0}, {{1.0, 0.0}}}};
  transformTrajectories(t, {10, 0, kPi / 2}, 2.0, 5.0);
  EXPECT_NEAR(t[0].p[0].x, 10.0, 1e-12);
  EXPECT_NEAR(t[0].p[0].y, 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(t[0].t[0], 5.0);
}

TEST(FreeSpace, AStarFindsAPathThroughTheDoorGap) {
  // two rooms separated by a wall at x = 5 with a 1 m gap at y in [4, 5]
  const World w = parseWorld(
      "walls:\n  - [[0,0],[10,0],[10,10],[0,10],[0,0]]\n  - [[5,0],[5,4]]\n  - [[5,5],[5,10]]\n"
      "regions: [{name: a, rect: [0,0,5,10]}, {name: b, rect: [5,0,10,10]}]\n",
      "t.yaml");
  const FreeSpaceGrid grid(w, 0.1, 0.3);
  const auto path = grid.plan({2, 1}, {8, 1});
  ASSERT_GE(path.size(), 3u);
  bool through_gap = false;
  double length = 0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    length += norm(path[i] - path[i - 1]);
    const Vec2 a = path[i - 1], b = path[i];
    if ((a.x - 5) * (b.x - 5) <= 0) {
      const double y = a.y + (b.y - a.y) * (5 - a.x) / (b.x - a.x);
      through_gap = y > 4.2 && y < 4.8;
    }
  }
  EXPECT_TRUE(through_gap);
  EXPECT_LT(length, 2 * std::hypot(3.0, 3.5) + 0.5);  // close to the shortest path via the gap
  EXPECT_TRUE(grid.plan({2, 1}, {5, 2}).empty());     // goal inside the wall clearance
}

TEST(PeopleSimulator, ScriptedWalkerAndRecordedTrajectory) {
  const World w = parseWorld(
      "walls: [[[-20,-20],[20,-20],[20,20],[-20,20],[-20,-20]]]\n"
      "people:\n  - {kind: scripted, waypoints: [[0,0],[4,0]], speed: 1.0, start_time: 1.0}\n",
      "t.yaml");
  PeopleSimulator ps(w, GaitConfig{}, Rng(1));
  ps.update(0.5);
  EXPECT_TRUE(ps.people().empty());  // not yet started
  ps.update(1.0);
  ps.update(3.0);
  ASSERT_EQ(ps.people().size(), 1u);
  EXPECT_NEAR(ps.people()[0].position.x, 2.0, 1e-9);
  ps.update(7.0);  // 4 m out, 2 m back (loop closes to the first waypoint)
  EXPECT_NEAR(ps.people()[0].position.x, 2.0, 1e-9);
  EXPECT_NEAR(std::abs(ps.people()[0].heading), kPi, 1e-9);
  std::vector<Circle> legs;
  ps.legCircles(legs);
  ASSERT_EQ(legs.size(), 2u);
  EXPECT_NEAR(norm(0.5 * (legs[0].center + legs[1].center) - ps.people()[0].position), 0.0, 1e-12);

  ps.addTrajectories({{99, {10.0, 12.0}, {{0, 5}, {2, 5}}}}, false);
  ps.update(11.0);
  ASSERT_EQ(ps.people().size(), 2u);
  EXPECT_NEAR(ps.people()[1].position.x, 1.0, 1e-12);
  EXPECT_NEAR(ps.people()[1].velocity.x, 1.0, 1e-12);
  ps.update(12.5);
  EXPECT_EQ(ps.people().size(), 1u);  // trajectory over
}

TEST(PeopleSimulator, CrowdRatesFollowTimeOfDay) {
  // One source, one sink; the rate peaks at noon and is zero at midnight (amplitude 1).
  const World w = parseWorld(
      "walls: [[[0,0],[20,0],[20,10],[0,10],[0,0]]]\n"
      "regions: [{name: door, rect: [0.5,0.5,2,9.5]}, {name: sink, rect: [18,0.5,19.5,9.5]}]\n"
      "crowd: {sources: [door], sinks: [sink], base_rate: 60, terms: [{period: 86400, amplitude: 1.0, phase: 43200}],"
      " speed: 1.2, max_people: 1000}\n",
      "t.yaml");
  EXPECT_NEAR(w.crowd->rateAt(43200) * 3600, 120.0, 1e-9);
  EXPECT_NEAR(w.crowd->rateAt(0) * 3600, 0.0, 1e-9);
  PeopleSimulator ps(w, GaitConfig{}, Rng(11));
  ps.update(0.0);
  int night = 0, noon = 0;
  // two one-hour windows: 00:00-01:00 (expected ~1 arrival) and 11:30-12:30 (expected ~120)
  for (double t = 1.0; t <= 3600.0; t += 1.0) ps.update(t);
  night = ps.spawnedCrowd();
  PeopleSimulator ps2(w, GaitConfig{}, Rng(11));
  ps2.update(41400.0);
  for (double t = 41401.0; t <= 45000.0; t += 1.0) {
    ps2.update(t);
    for (const auto& p : ps2.people()) {
      ASSERT_GT(p.position.x, 0.3);
      ASSERT_LT(p.position.x, 19.7);
    }
  }
  noon = ps2.spawnedCrowd();
  EXPECT_LE(night, 5);
  EXPECT_GT(noon, 90);
  EXPECT_LT(noon, 150);
}

TEST(PeopleSimulator, WorldPeopleSectionWithRecordedEthData) {
  // A world that places the ETH excerpt with an offset (rotation by 90°, shift) and loops it.
  const std::string yaml = "walls: [[[-50,-50],[50,-50],[50,50],[-50,50],[-50,-50]]]\n"
                           "people:\n  - {kind: eth_obsmat, file: " +
                           kPeopleData +
                           "eth_seq_eth_obsmat_head400.txt, offset: [1, 2, 1.5707963267948966], time_offset: -52,"
                           " loop: true}\n";
  const World w = parseWorld(yaml, "/tmp/eth_world.yaml");
  ASSERT_EQ(w.people.size(), 1u);
  PeopleSimulator ps(w, GaitConfig{}, Rng(1));
  // pedestrian 1 starts at frame 780 -> t = 52 s -> sim t = 0 after the time offset; data (8.457, 3.588)
  // rotated by +90°: (-3.588, 8.457) + (1, 2)
  ps.update(0.0);
  ASSERT_FALSE(ps.people().empty());
  const PersonState& p = ps.people().front();
  EXPECT_EQ(p.id, 1);
  EXPECT_NEAR(p.position.x, 1 - 3.5880664, 1e-6);
  EXPECT_NEAR(p.position.y, 2 + 8.4568443, 1e-6);
  // walking direction rotated too: the recorded v is mostly +x -> now mostly +y
  EXPECT_NEAR(p.heading, std::numbers::pi / 2, 0.3);
  // loop: the whole excerpt repeats, so people are present again one period later
  std::size_t max_people = 0;
  for (double t = 0.0; t < 200.0; t += 0.5) {
    ps.update(t);
    max_people = std::max(max_people, ps.people().size());
  }
  EXPECT_GE(max_people, 3u);
  EXPECT_THROW(parseWorld("walls: [[[0,0],[1,0]]]\npeople: [{kind: csv, file: nothere.csv}]\n", "/tmp/x.yaml"), InputError);
  try {
    parseWorld("walls: [[[0,0],[1,0]]]\npeople: [{kind: csv, file: /tmp}]\n", "x.yaml");
    ADD_FAILURE() << "a directory was accepted as a people file";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "x.yaml:2: 'people[0].file': '/tmp' is a directory, not a file");
  }
}

TEST(FreeSpace, AWorldTooLargeForTheGridIsAnInputError) {
  // a wall 1e12 m long used to make the crowd's grid allocate until std::bad_alloc (or the OOM killer)
  const World w = parseWorld("walls: [[[0, 0], [1e12, 0], [10, 5]]]\n", "long.yaml");
  try {
    FreeSpaceGrid grid(w);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("long.yaml:0: crowd: the world's extent of 1e+12 x 5 m is too large", 0), 0u)
        << e.what();
  }
}

TEST(FreeSpace, ClosedDoorsBlockPlanning) {
  const World w = parseWorld(
      "walls:\n  - [[0,0],[10,0],[10,10],[0,10],[0,0]]\n  - [[5,0],[5,4]]\n  - [[5,5],[5,10]]\n"
      "doors: [{hinge: [5, 4], latch: [5, 5], schedule: [{t: 0, open: true}, {t: 100, open: false}]}]\n",
      "t.yaml");
  FreeSpaceGrid grid(w, 0.1, 0.3);
  grid.setDoorTime(w, 50.0);
  EXPECT_FALSE(grid.plan({2, 1}, {8, 1}).empty());
  grid.setDoorTime(w, 150.0);
  EXPECT_TRUE(grid.plan({2, 1}, {8, 1}).empty());  // the only passage is closed
  EXPECT_FALSE(grid.plan({2, 1}, {2, 8}).empty()); // same room: still reachable
}

namespace {
struct Approach {
  double min_centre = 1e9;  ///< closest centre distance
  double min_legs = 1e9;    ///< closest leg-to-leg (different people) or leg-to-robot centre distance
  std::vector<Vec2> end;
};
// Walkers of `yaml` (a big empty room) for `duration` s at 100 Hz, optionally with a robot at `robot`.
Approach walk(const std::string& people_yaml, double duration, const SocialForceConfig& social,
              std::optional<Vec2> robot = std::nullopt, double robot_radius = 0.28) {
  const World w = parseWorld("walls: [[[-20,-20],[30,-20],[30,20],[-20,20],[-20,-20]]]\npeople:\n" + people_yaml, "t.yaml");
  PeopleSimulator ps(w, GaitConfig{}, Rng(3));
  ps.setSocialForce(social);
  if (robot) ps.setRobot(*robot, robot_radius);
  Approach r;
  for (int k = 0; k <= std::lround(duration * 100); ++k) {
    ps.update(k * 0.01);
    const auto& p = ps.people();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (robot) {
        r.min_centre = std::min(r.min_centre, norm(p[i].position - *robot));
        for (const auto& l : p[i].legs) r.min_legs = std::min(r.min_legs, norm(l - *robot));
      }
      for (std::size_t j = i + 1; j < p.size(); ++j) {
        r.min_centre = std::min(r.min_centre, norm(p[i].position - p[j].position));
        for (const auto& a : p[i].legs)
          for (const auto& b : p[j].legs) r.min_legs = std::min(r.min_legs, norm(a - b));
      }
    }
  }
  for (const auto& p : ps.people()) r.end.push_back(p.position);
  return r;
}
const std::string kHeadOn =
    "  - {kind: scripted, waypoints: [[0,0],[10,0],[20,0]], speed: 1.2, start_time: 0}\n"
    "  - {kind: scripted, waypoints: [[20,0],[10,0],[0,0]], speed: 1.0, start_time: 0}\n";
}  // namespace

TEST(SocialForce, HeadOnWalkersPassEachOtherWithoutOverlapping) {
  SocialForceConfig off;
  off.enabled = false;
  const Approach blind = walk(kHeadOn, 15.0, off);
  EXPECT_LT(blind.min_centre, 0.05) << "without the social force they walk through each other (test is meaningful)";

  const Approach a = walk(kHeadOn, 15.0, SocialForceConfig{});
  // Bodies (2 × body_radius = 0.5 m) may be squeezed a little, legs never touch: a sensible bound well above
  // 2 leg radii between any two legs of different people.
  EXPECT_GT(a.min_centre, 0.45);
  EXPECT_GT(a.min_legs, 4 * GaitConfig{}.leg_radius);
  // They got past each other (no deadlock) and went on along their paths.
  ASSERT_EQ(a.end.size(), 2u);
  EXPECT_GT(a.end[0].x, 15.0);
  EXPECT_LT(a.end[1].x, 7.0);
  EXPECT_LT(std::abs(a.end[0].y) + std::abs(a.end[1].y), 1.0) << "back on their lines after passing";
}

TEST(SocialForce, AWalkerDoesNotWalkThroughTheRobot) {
  const std::string one = "  - {kind: scripted, waypoints: [[0,0],[10,0],[20,0]], speed: 1.0, start_time: 0}\n";
  SocialForceConfig off;
  off.enabled = false;
  EXPECT_LT(walk(one, 12.0, off, Vec2{8, 0}).min_centre, 0.05);
  const Approach a = walk(one, 12.0, SocialForceConfig{}, Vec2{8, 0});
  EXPECT_GT(a.min_centre, 0.28 + 0.2);  // robot footprint + more than the hip half width
  EXPECT_GT(a.min_legs, 0.28 + GaitConfig{}.leg_radius) << "a leg inside the robot's footprint";
  ASSERT_EQ(a.end.size(), 1u);
  EXPECT_GT(a.end[0].x, 11.0) << "walked around the robot";
}

TEST(SocialForce, CrowdStaysDeterministicForASeed) {
  // The office crowd at its busiest (start_time: the daily term's peak) for 20 simulated minutes, twice.
  World w = loadWorld(resolveWorldPath("office"));
  ASSERT_TRUE(w.crowd.has_value());
  w.crowd->start_time = w.crowd->terms.front().phase;
  w.crowd->base_rate *= 10;
  const auto run = [&](std::uint64_t seed) {
    PeopleSimulator ps(w, GaitConfig{}, Rng(seed));
    std::vector<double> trace;
    for (int k = 0; k <= 1200; ++k) {
      ps.update(k * 1.0);
      for (const auto& p : ps.people()) trace.insert(trace.end(), {double(p.id), p.position.x, p.position.y, p.heading});
    }
    return std::make_pair(trace, ps.spawnedCrowd());
  };
  const auto a = run(11), b = run(11), c = run(12);
  EXPECT_GT(a.second, 10);
  EXPECT_TRUE(a.first == b.first) << "same seed, different trajectories";
  EXPECT_FALSE(a.first == c.first);
}

TEST(Crowd, StartTimeShiftsTheSchedule) {
  World w = parseWorld(
      "walls: [[[0,0],[10,0],[10,10],[0,10],[0,0]]]\n"
      "regions: [{name: a, rect: [1,1,3,3]}, {name: b, rect: [7,7,9,9]}]\n"
      "crowd: {sources: [a], sinks: [b], base_rate: 10, start_time: 21600,\n"
      "        terms: [{period: 86400, amplitude: 0.9, phase: 43200}, {period: 604800, amplitude: 0.3, phase: 0}]}\n",
      "t.yaml");
  ASSERT_TRUE(w.crowd.has_value());
  EXPECT_EQ(w.crowd->start_time, 21600.0);
  CrowdConfig shifted = *w.crowd, plain = *w.crowd;
  plain.start_time = 0;
  for (double t : {0.0, 1000.0, 21600.0, 50000.0, 300000.0}) EXPECT_DOUBLE_EQ(shifted.rateAt(t), plain.rateAt(t + 21600.0));
  EXPECT_GT(shifted.rateAt(21600.0), shifted.rateAt(0.0));  // t = 6 h of sim time is noon of the schedule
}
