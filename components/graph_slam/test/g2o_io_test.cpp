// g2o reader/writer: round trip, every bad-input class reported with file:line, information fixing.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>

#include "cairn/graph_slam/g2o_io.hpp"

namespace gs = cairn::graph_slam;

namespace {

const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/pose_graph/";

gs::PoseGraph parse(const std::string& text, const gs::G2oReadOptions& opt = {}, gs::G2oReadReport* rep = nullptr) {
  std::istringstream in(text);
  return gs::readG2o(in, "t.g2o", opt, rep);
}

// Expects a G2oError at `line` whose message contains `what`.
void expectError(const std::string& text, std::size_t line, const std::string& what) {
  try {
    parse(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const gs::G2oError& e) {
    EXPECT_EQ(e.file(), "t.g2o");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(e.message().find(what), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("t.g2o:" + std::to_string(line) + ": ", 0), 0u) << e.what();
  }
}

const std::string kTwo = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";

}  // namespace

TEST(G2oIo, ReadsIntelAndRoundTripsExactly) {
  const gs::PoseGraph g = gs::readG2o(kData + "input_INTEL_g2o.g2o");
  EXPECT_EQ(g.variables().size(), 1228u);
  EXPECT_EQ(g.factors().size(), 1483u);
  std::stringstream buf;
  gs::writeG2o(g, buf);
  const gs::PoseGraph h = gs::readG2o(buf, "roundtrip");
  ASSERT_EQ(h.variables().size(), g.variables().size());
  ASSERT_EQ(h.factors().size(), g.factors().size());
  for (std::size_t k = 0; k < g.variables().size(); ++k) {
    EXPECT_EQ(h.variables()[k].id, g.variables()[k].id);
    EXPECT_EQ(h.variables()[k].pose2.t, g.variables()[k].pose2.t);
    EXPECT_EQ(h.variables()[k].pose2.theta, g.variables()[k].pose2.theta);
  }
  for (std::size_t k = 0; k < g.factors().size(); ++k) {
    EXPECT_EQ(h.factors()[k].information, g.factors()[k].information);
    EXPECT_EQ(h.factors()[k].z2.t, g.factors()[k].z2.t);
  }
  EXPECT_EQ(h.chi2(), g.chi2());
}

TEST(G2oIo, AllTagsRoundTrip) {
  const std::string text =
      "# comment line\n"
      "VERTEX_SE2 0 0 0 0\n"
      "VERTEX_SE2 1 1.5 -0.25 0.1\n"
      "VERTEX_XY 7 2 3\n"
      "\n"
      "VERTEX_SE3:QUAT 10 1 2 3 0 0 0.70710678118654757 0.70710678118654757\n"
      "VERTEX_SE3:QUAT 11 1 2 4 0 0 0 1\n"
      "FIX 0\n"
      "EDGE_SE2 0 1 1 0 0.1 10 0 0 10 0 20\n"
      "EDGE_SE2_XY 1 7 1 3 5 0.5 5\n"
      "EDGE_PRIOR_SE2 1 1.5 -0.25 0.1 1 0 0 1 0 1\n"
      "EDGE_SE3:QUAT 10 11 0 0 1 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n";
  const gs::PoseGraph g = parse(text);
  EXPECT_EQ(g.variables().size(), 5u);
  EXPECT_EQ(g.factors().size(), 4u);
  EXPECT_TRUE(g.variable(0).fixed);
  EXPECT_EQ(g.variable(7).kind, gs::VariableKind::kPoint2);
  std::stringstream buf;
  gs::writeG2o(g, buf);
  const gs::PoseGraph h = gs::readG2o(buf, "rt");
  EXPECT_EQ(h.variables().size(), 5u);
  EXPECT_EQ(h.factors().size(), 4u);
  EXPECT_TRUE(h.variable(0).fixed);
  EXPECT_DOUBLE_EQ(h.chi2(), g.chi2());
  EXPECT_TRUE(h.pose3(10).q.isApprox(g.pose3(10).q, 1e-15));
}

TEST(G2oIo, BadInputIsReportedWithFileAndLine) {
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n", 3, "needs 11 fields, got 10");             // truncated
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1 9\n", 3, "needs 11 fields, got 12");         // extra
  expectError("VERTEX_SE2 0 0 0\n", 1, "truncated");
  expectError(kTwo + "EDGE_SE2 0 1 1 zero 0 1 0 0 1 0 1\n", 3, "'zero' is not a number");        // non-numeric
  expectError(kTwo + "EDGE_SE2 0 1 1 0x1 0 1 0 0 1 0 1\n", 3, "is not a number");
  expectError("VERTEX_SE2 0 nan 0 0\n", 1, "NaN/Inf");
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 inf 0 0 1 0 1\n", 3, "NaN/Inf");
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1e999\n", 3, "out of range");
  expectError(kTwo + "EDGE_SE2 0 5 1 0 0 1 0 0 1 0 1\n", 3, "missing vertex 5");                 // missing
  expectError(kTwo + "VERTEX_SE2 1 0 0 0\n", 3, "duplicate vertex id 1");                          // duplicate
  expectError("VERTEX_SE2 1.5 0 0 0\n", 1, "not an integer vertex id");
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n", 3, "not symmetric positive definite");  // non-SPD
  expectError(kTwo + "EDGE_SE2 0 1 1 0 0 1 2 0 1 0 1\n", 3, "not symmetric positive definite");   // indefinite
  expectError(kTwo + "VERTEX_FOO 3 1 2\n", 3, "unknown tag 'VERTEX_FOO'");
  expectError(kTwo + "FIX 9\n", 3, "missing vertex 9");
  expectError("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 0\n", 1, "zero norm");
  expectError(kTwo + "EDGE_SE2 0 0 1 0 0 1 0 0 1 0 1\n", 3, "with itself");
  expectError("VERTEX_SE2 0 0 0 0\nVERTEX_XY 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", 3, "needs a SE2 pose");
  EXPECT_THROW(gs::readG2o("/nonexistent/file.g2o"), gs::G2oError);
}

TEST(G2oIo, ClampProjectsNonSpdInformationAndCountsIt) {
  gs::G2oReadOptions opt;
  opt.information_fix = gs::G2oReadOptions::InformationFix::kClamp;
  gs::G2oReadReport rep;
  const gs::PoseGraph g = parse(kTwo + "EDGE_SE2 0 1 1 0 0 1 2 0 1 0 1\nEDGE_SE2 1 0 -1 0 0 1 0 0 1 0 1\n", opt, &rep);
  EXPECT_EQ(rep.clamped_information, 1u);
  const Eigen::Matrix3d info = g.factors()[0].information.topLeftCorner<3, 3>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(info);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
  // Nearest PSD of [[1,2],[2,1]] keeps the positive eigenpair (3, [1,1]/sqrt2).
  EXPECT_NEAR(info(0, 0), 1.5, 1e-6);
  EXPECT_NEAR(info(0, 1), 1.5, 1e-6);
  EXPECT_TRUE((g.factors()[1].information.topLeftCorner<3, 3>() == Eigen::Matrix3d::Identity()));
}

TEST(G2oIo, UnknownTagsCanBeSkippedWithAWarning) {
  gs::G2oReadOptions opt;
  opt.skip_unknown_tags = true;
  gs::G2oReadReport rep;
  const gs::PoseGraph g = parse(kTwo + "PARAMS_SE3OFFSET 0 0 0 0 0 0 0 1\nPARAMS_SE3OFFSET 1\n", opt, &rep);
  EXPECT_EQ(g.variables().size(), 2u);
  EXPECT_EQ(rep.skipped_lines, 2u);
  ASSERT_EQ(rep.warnings.size(), 1u);
  EXPECT_EQ(rep.warnings[0], "t.g2o:3: skipping unknown tag PARAMS_SE3OFFSET");
}
