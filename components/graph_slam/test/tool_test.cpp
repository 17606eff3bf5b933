// cairn-slam optimize: JSON summary keys, output file, and the bad-input contract (one line
// "cairn: <file>:<line>: <what>" on stderr, exit code 2).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "cairn/graph_slam/g2o_io.hpp"

namespace {

const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/pose_graph/";

struct ToolRun {
  int code;
  std::string out, err;
};

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

ToolRun run(const std::string& args) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string out = (dir / "cairn_slam_tool_test.out").string(), err = (dir / "cairn_slam_tool_test.err").string();
  const int status = std::system((std::string(CAIRN_SLAM_TOOL) + " " + args + " >" + out + " 2>" + err).c_str());
  return ToolRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace

TEST(Tool, OptimizeJsonHasExactlyTheDocumentedKeys) {
  const std::string out_file = (std::filesystem::temp_directory_path() / "cairn_slam_tool_test.g2o").string();
  const ToolRun r = run("optimize " + kData + "intel.g2o --json --solver dogleg -o " + out_file);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::regex re(
      R"(^\{"vertices":943,"edges":1837,"initial_chi2":[0-9.e+-]+,"final_chi2":[0-9.e+-]+,"iterations":[0-9]+,)"
      R"("time_s":[0-9.e+-]+,"converged":true\}\n$)");
  EXPECT_TRUE(std::regex_match(r.out, re)) << r.out;
  const auto g = cairn::graph_slam::readG2o(out_file);
  EXPECT_EQ(g.variables().size(), 943u);
  EXPECT_LT(g.chi2(), 600.0);  // optimized values were written
}

TEST(Tool, OptimizeCertifyAddsTheCertificateObject) {
  // The documented keys stay first and unchanged; --certify appends one object (intel: certified, see
  // docs/benchmarks.md "Global optimum").
  const ToolRun r = run("optimize " + kData + "intel.g2o --json --certify");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::regex re(
      R"(^\{"vertices":943,"edges":1837,"initial_chi2":[0-9.e+-]+,"final_chi2":[0-9.e+-]+,"iterations":[0-9]+,)"
      R"("time_s":[0-9.e+-]+,"converged":true,"certificate":\{"certified":true,"sesync_objective":[0-9.e+-]+,)"
      R"("refined_objective":[0-9.e+-]+,"dual_bound":[0-9.e+-]+,"lambda_min":[0-9.e+-]+,"eta":[0-9.e+-]+,)"
      R"("refine_iterations":[0-9]+,"refine_converged":true,"time_s":[0-9.e+-]+\}\}\n$)");
  EXPECT_TRUE(std::regex_match(r.out, re)) << r.out;
}

TEST(Tool, BadInputGivesFileLineAndExitCode2) {
  const std::string bad = (std::filesystem::temp_directory_path() / "cairn_slam_bad.g2o").string();
  std::ofstream(bad) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n";
  ToolRun r = run("optimize " + bad + " --json");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(r.out.empty());
  EXPECT_EQ(r.err, "cairn: " + bad + ":3: information matrix is not symmetric positive definite (use "
                   "--fix-information clamp to project it)\n");
  r = run("optimize " + bad + " --json --fix-information clamp");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("projected 1 information matrices"), std::string::npos) << r.err;

  r = run("optimize /nonexistent.g2o");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: /nonexistent.g2o:0: cannot open file\n");
  r = run("optimize " + bad + " --solver newton");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown solver 'newton'"), std::string::npos);
  for (const char* t : {"inf", "-1", "0.5x"}) {  // an infinite GNC inlier threshold was accepted
    r = run("optimize " + bad + " --robust gnc:" + t);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(std::string("gnc threshold must be a positive number, got '") + t + "'"), std::string::npos)
        << r.err;
  }
}

namespace {

std::string tempFile(const std::string& name, const std::string& text) {
  const std::string p = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::size_t lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace

TEST(Tool, OptimizeRejectsOverflowingEmptyAndHugeLines) {
  // Finite numbers whose chi2 overflows: an error naming the edge's line, not "chi2: null, converged".
  const std::string huge = tempFile("cairn_slam_huge.g2o",
                                    "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1e300 0 0\n"
                                    "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n");
  ToolRun r = run("optimize " + huge + " --json");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(r.err, "cairn: " + huge +
                       ":3: the edge's chi2 at the initial values is not finite (values too large)\n");

  const std::string empty = tempFile("cairn_slam_empty.g2o", "# nothing\n");
  r = run("optimize " + empty);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: " + empty + ":0: no vertices (empty graph)\n");

  // A 1 MB garbage token is quoted in at most a few dozen characters.
  const std::string garbage =
      tempFile("cairn_slam_garbage.g2o", "VERTEX_SE2 0 0 0 " + std::string(1 << 20, 'x') + "\n");
  r = run("optimize " + garbage);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.err), 1u);
  EXPECT_LT(r.err.size(), 200u) << r.err.substr(0, 300);
  EXPECT_NE(r.err.find(":1: field 4 'xxxxxxxx"), std::string::npos) << r.err.substr(0, 300);
  r = run("optimize " + std::filesystem::temp_directory_path().string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(":0: cannot open file: is a directory"), std::string::npos) << r.err;
}

TEST(Tool, RunAndEvalRejectBadOptionsAndFiles) {
  const std::string tmp = std::filesystem::temp_directory_path().string();
  const std::string out = tmp + "/cairn_slam_run_bad";
  // Scan stamps going backwards (real logs have some: Intel): a warning naming the first one, SLAM drops
  // them, and the data duration is the stamps' span (it was last - first = -69 s here, with a negative
  // real-time factor).
  std::string beams, text;
  for (int i = 0; i < 180; ++i) beams += " 2.00";
  for (const char* stamp : {"100.000000", "31.000000", "101.000000"})
    text += "FLASER 180" + beams + " 0 0 0 0 0 0 " + stamp + " nohost " + stamp + "\n";
  const std::string log = tempFile("cairn_slam_backwards.log", text);
  ToolRun r = run("run --carmen " + log + " --out " + out + " --quiet --json");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "cairn: slam: warning: " + log +
                       ":2: scan timestamp before an earlier scan's (1 such scans; "
                       "SLAM rejects them)\n");
  EXPECT_NE(r.out.find("\"scans\":3,\"scans_rejected\":1,"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"data_duration_s\":70,"), std::string::npos) << r.out;
  // No scan accepted (3 beams < filter.min_points): an error, not an OpenCV assertion on the empty map.
  const std::string tiny =
      tempFile("cairn_slam_tiny.log", "FLASER 3 1.00 2.00 3.00 0 0 0 0 0 0 100.0 nohost 100.0\n");
  r = run("run --carmen " + tiny + " --out " + out + " --quiet");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: " + tiny +
                       ": none of the 1 scans was accepted by SLAM (1 rejected: too few valid "
                       "returns, or time going backwards)\n");
  r = run("run --carmen " + log + " --out " + out + " --limit -1");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: --limit must be >= 1 scan\n");
  r = run("run --carmen " + log + " --out " + out + " --set laser_x=nan");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: laser_x: expected a number, got 'nan'\n");
  r = run("run --carmen " + log + " --out " + out + " --set laser_x=inf");  // was taken as a number outside the range
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: laser_x: expected a number, got 'inf'\n");
  r = run("run --carmen " + log + " --out " + out + " --set r_min=5000");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: r_min: 5000 is outside [0, 1000]\n");
  r = run("run --carmen " + log + " --out " + out + " --config " + tmp);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: " + tmp + ":0: cannot open file: is a directory\n");
  const std::string garbage =
      tempFile("cairn_slam_garbage.yaml", std::string("r_min: 3\n\xfe\x80\\\n\x00garbage\x7f", 16));
  r = run("run --carmen " + log + " --out " + out + " --config " + garbage);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: " + garbage + ":3: not a text file (control byte 0x00)\n");

  const std::string poses = tempFile("cairn_slam_eval_poses.txt", "1 0 0 0\n2 1 0 0\n");
  const std::string rel = tempFile("cairn_slam_eval.relations", "1 2 1 0 0 0 0 0\n");
  r = run("eval --poses " + poses + " --relations " + rel + " --stamp-tolerance -1");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: --stamp-tolerance must be >= 0 s\n");
  r = run("eval --poses " + tmp + " --relations " + rel);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: " + tmp + ":0: cannot open file: is a directory\n");
  r = run("eval --poses " + poses + " --relations " + tmp);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: " + tmp + ":0: cannot open file: is a directory\n");
  r = run("eval --poses " + poses + " --relations " + rel);
  EXPECT_EQ(r.code, 0) << r.err;
}

// The "laser_mount" array and "laser_mount_source" of a `run --json` line, e.g. "0.1 0 0 log".
static std::string mountOf(const std::string& json) {
  const std::regex re("\"laser_mount\":\\[([^,]+),([^,]+),([^\\]]+)\\],\"laser_mount_source\":\"([a-z]+)\"");
  std::smatch m;
  if (!std::regex_search(json, m, re)) return "no laser_mount in: " + json.substr(0, 200);
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.6g %.6g %.6g %s", std::stod(m[1]), std::stod(m[2]), std::stod(m[3]), m[4].str().c_str());
  return buf;
}

TEST(Tool, RunTakesTheLaserMountFromTheLogUnlessParametersGiveIt) {
  // FLASER: laser pose (0.1, 0, 0) and odometry pose (0, 0, 0) -> the mount is 0.1 m forward.
  std::string beams, text;
  for (int i = 0; i < 180; ++i) beams += " 2.00";
  for (const char* stamp : {"100.000000", "100.100000", "100.200000"})
    text += "FLASER 180" + beams + " 0.1 0 0 0 0 0 " + std::string(stamp) + " nohost " + stamp + "\n";
  const std::string log = tempFile("cairn_slam_mount.log", text);
  const std::string out = std::filesystem::temp_directory_path().string() + "/cairn_slam_run_mount";
  ToolRun r = run("run --carmen " + log + " --out " + out + " --quiet --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(mountOf(r.out), "0.1 0 0 log");
  // A mount given as parameters (--set or --config) wins: it was silently replaced by the log's.
  r = run("run --carmen " + log + " --out " + out + " --quiet --json --set laser_x=0.3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(mountOf(r.out), "0.3 0 0 parameters");
  const std::string cfg = tempFile("cairn_slam_mount.yaml", "laser_theta: 0.5\n");
  r = run("run --carmen " + log + " --out " + out + " --quiet --json --config " + cfg);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(mountOf(r.out), "0 0 0.5 parameters");
  r = run("run --carmen " + log + " --out " + out + " --quiet --json --laser-mount zero");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(mountOf(r.out), "0 0 0 parameters");
}

TEST(Tool, ReadmeParameterTableIsTheToolsOwn) {
  // The README's table is the component's parameter list: it must be what `cairn slam params --markdown` prints
  // (it had drifted: a wrong default and eight missing keys).
  const ToolRun r = run("params --markdown");
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_GT(std::count(r.out.begin(), r.out.end(), '\n'), 50) << r.out;
  const std::string readme = slurp(std::string(CAIRN_SOURCE_ROOT) + "/components/graph_slam/README.md");
  EXPECT_NE(readme.find(r.out), std::string::npos)
      << "components/graph_slam/README.md: paste the output of `cairn slam params --markdown` into \"### Parameters\"";
}

TEST(Tool, VerbHelpPrintsTheUsageAndEvalRefusesAnOdometryBaselineWithoutRelations) {
  for (const char* verb : {"optimize", "run", "eval", "params", "train-verifier", "eval-verifier"}) {
    const ToolRun r = run(std::string(verb) + " --help");
    EXPECT_EQ(r.code, 0) << verb << ": " << r.err;  // was "unknown option '--help'", exit 2
    EXPECT_NE(r.out.find("cairn slam eval-verifier"), std::string::npos) << verb;
  }
  ToolRun r = run("nonsense --help");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown verb 'nonsense'"), std::string::npos) << r.err;
  // The odometry baseline is scored on the relations; without them it was silently ignored.
  r = run("eval --poses p.txt --odometry-baseline raw.log --corrected c.log --carmen raw.log");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "cairn: slam: --odometry-baseline needs --relations\n");
}
