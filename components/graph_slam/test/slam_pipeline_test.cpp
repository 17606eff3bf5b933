// SLAM pipeline tests: relations metric, map exports, `cairn slam eval`/`run`, save/load, end to end on a log excerpt.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "cairn/graph_slam/occupancy_grid.hpp"
#include "cairn/graph_slam/relations.hpp"
#include "cairn/sim/world.hpp"

namespace gs = cairn::graph_slam;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("cairn_slam_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

void writeText(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

// Runs the cairn-slam tool; returns the exit code, stdout in `out`.
int runTool(const std::string& args, std::string& out) {
  const fs::path o = fs::temp_directory_path() / ("cairn_slam_tool_out_" + std::to_string(::getpid()));
  const int rc = std::system((std::string(CAIRN_SLAM_TOOL) + " " + args + " > " + o.string() + " 2>&1").c_str());
  std::ifstream in(o);
  out.assign(std::istreambuf_iterator<char>(in), {});
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(Relations, PerfectTrajectoryHasZeroErrorAndKnownPerturbationIsMeasured) {
  // A trajectory on a circle; relations between every pair 5 apart, taken from the truth.
  std::vector<gs::StampedPose> truth;
  for (int i = 0; i < 50; ++i) {
    const double a = 0.1 * i;
    truth.push_back({100.0 + i, {{5 * std::cos(a), 5 * std::sin(a)}, gs::normalizeAngle(a + M_PI / 2)}});
  }
  std::vector<gs::Relation> rel;
  for (int i = 0; i + 5 < 50; ++i)
    rel.push_back({truth[i].stamp, truth[i + 5].stamp, gs::compose(gs::inverse(truth[i].pose), truth[i + 5].pose), i + 1});
  auto r = gs::evaluateRelations(rel, truth);
  EXPECT_EQ(r.used, rel.size());
  EXPECT_NEAR(r.trans_mean, 0.0, 1e-12);
  EXPECT_NEAR(r.rot_mean, 0.0, 1e-12);

  // Rotate pose 20 by 1 degree about itself: the relations touching it get exactly that rotational error.
  auto bent = truth;
  bent[20].pose.theta += M_PI / 180.0;
  r = gs::evaluateRelations(rel, bent);
  EXPECT_NEAR(r.rot_max, M_PI / 180.0, 1e-9);
  EXPECT_NEAR(r.rot_mean, 2.0 / static_cast<double>(rel.size()) * M_PI / 180.0, 1e-9);
  EXPECT_GT(r.trans_max, 0.0);  // the rotation also moves the partner in pose 20's frame

  // A global rigid transform of the whole trajectory changes nothing (the metric is relative).
  auto moved = truth;
  const gs::Pose2 g{{3.0, -2.0}, 0.7};
  for (auto& p : moved) p.pose = gs::compose(g, p.pose);
  r = gs::evaluateRelations(rel, moved);
  EXPECT_NEAR(r.trans_mean, 0.0, 1e-9);
  EXPECT_NEAR(r.rot_mean, 0.0, 1e-9);

  // Missing stamps are counted, not guessed.
  auto partial = truth;
  partial.erase(partial.begin() + 10);
  r = gs::evaluateRelations(rel, partial);
  EXPECT_EQ(r.missing, 2u);
  EXPECT_EQ(r.used, rel.size() - 2);
}

TEST(Relations, ReadersNameFileAndLine) {
  const fs::path d = tempDir("readers");
  writeText(d / "r.relations", "# comment\n1 2 0.5 0 0 0 0 0.1\n1 2 x 0 0 0 0 0\n");
  try {
    gs::readRelations((d / "r.relations").string());
    FAIL() << "expected InputError";
  } catch (const cairn::sim::InputError& e) {
    EXPECT_EQ(e.line(), 3);
  }
  writeText(d / "p.txt", "1 0 0 0\n2 1 0\n");
  EXPECT_THROW(gs::readPoses((d / "p.txt").string()), cairn::sim::InputError);
  EXPECT_THROW(gs::readPoses((d / "missing.txt").string()), cairn::sim::InputError);
}

TEST(SlamTool, EvalPrintsJsonAndRejectsBadInput) {
  const fs::path d = tempDir("eval");
  writeText(d / "poses.txt", "1.0 0 0 0\n2.0 1 0 0.1\n");
  writeText(d / "ok.relations", "1.0 2.0 1.05 0 0 0 0 0.1\n");
  std::string out;
  ASSERT_EQ(runTool("eval --json --relations " + (d / "ok.relations").string() + " --poses " + (d / "poses.txt").string(), out), 0) << out;
  EXPECT_NE(out.find("\"trans_mean_m\":0.05"), std::string::npos) << out;
  EXPECT_NE(out.find("\"used\":1"), std::string::npos) << out;

  writeText(d / "bad.relations", "1.0 2.0 1.05 0 0 0 0 0.1\n1.0 2.0 nan\n");
  EXPECT_EQ(runTool("eval --relations " + (d / "bad.relations").string() + " --poses " + (d / "poses.txt").string(), out), 2);
  EXPECT_NE(out.find("bad.relations:2:"), std::string::npos) << out;

  writeText(d / "missing.relations", "1.0 3.0 1.05 0 0 0 0 0.1\n");
  EXPECT_EQ(runTool("eval --relations " + (d / "missing.relations").string() + " --poses " + (d / "poses.txt").string(), out), 2);
  EXPECT_NE(out.find("missing.relations:1:"), std::string::npos) << out;
  EXPECT_EQ(runTool("eval --bogus", out), 2);
}

TEST(MapExport, PgmYamlAndPngFollowMapServerConventions) {
  gs::OccupancyGrid g;
  g.resolution = 0.1;
  g.origin = {-1.0, 2.0};
  g.width = 4;
  g.height = 3;
  g.data = {0, 100, -1, 50,  //
            0, 0, 0, 0,      //
            -1, -1, -1, 100};
  EXPECT_EQ(g.knownCells(), 8u);
  const fs::path d = tempDir("export");
  gs::writeMapServer(g, (d / "map").string());
  std::ifstream pgm(d / "map.pgm", std::ios::binary);
  std::string magic, comment;
  std::getline(pgm, magic);
  std::getline(pgm, comment);
  int w = 0, h = 0, maxv = 0;
  pgm >> w >> h >> maxv;
  pgm.get();
  ASSERT_EQ(magic, "P5");
  ASSERT_EQ(w, 4);
  ASSERT_EQ(h, 3);
  std::string pix(12, '\0');
  pgm.read(pix.data(), 12);
  // Top image row is the highest y row of the grid (row 2): unknown x3, occupied.
  EXPECT_EQ(static_cast<unsigned char>(pix[0]), 205);
  EXPECT_EQ(static_cast<unsigned char>(pix[3]), 0);
  // Bottom image row = grid row 0: free, occupied, unknown, in-between (unknown grey).
  EXPECT_EQ(static_cast<unsigned char>(pix[8]), 254);
  EXPECT_EQ(static_cast<unsigned char>(pix[9]), 0);
  EXPECT_EQ(static_cast<unsigned char>(pix[10]), 205);
  std::ifstream yaml(d / "map.yaml");
  std::string y((std::istreambuf_iterator<char>(yaml)), {});
  EXPECT_NE(y.find("image: map.pgm"), std::string::npos) << y;
  EXPECT_NE(y.find("origin: [-1.000000, 2.000000, 0.0]"), std::string::npos) << y;
  gs::writeMapPng(g, {{{-0.95, 2.05}, 0.0}, {{-0.65, 2.25}, 0.0}}, (d / "map.png").string());
  EXPECT_GT(fs::file_size(d / "map.png"), 0u);
  EXPECT_THROW(gs::writeMapServer(g, (d / "no_such_dir" / "map").string()), std::runtime_error);
}
