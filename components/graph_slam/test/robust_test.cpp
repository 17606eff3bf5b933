// Robustness to false loop closures at a small scale (the full M3500 + 1000 outliers experiment is in
// cairn-slam-bench --outliers): the g2o Intel graph with 100 random false loop closures added.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/gnc.hpp"
#include "cairn/graph_slam/optimizer.hpp"

namespace gs = cairn::graph_slam;

namespace {

const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/pose_graph/";

std::size_t addFalseLoopClosures(gs::PoseGraph& g, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(g.variables().size()) - 1);
  std::uniform_real_distribution<double> ut(-2.0, 2.0), ua(-M_PI, M_PI);
  const Eigen::Matrix3d info = g.factors().back().information.topLeftCorner<3, 3>();
  const std::size_t first = g.factors().size();
  for (int k = 0; k < count;) {
    const int i = pick(rng), j = pick(rng);
    if (std::abs(i - j) < 2) continue;
    g.addBetween2(g.variables()[i].id, g.variables()[j].id, gs::Pose2{Eigen::Vector2d(ut(rng), ut(rng)), ua(rng)},
                  info);
    ++k;
  }
  return first;
}

// RMS position difference (same gauge: vertex 0 is fixed by the automatic gauge in both).
double rmsDiff(const gs::PoseGraph& a, const gs::PoseGraph& b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.variables().size(); ++k) {
    s += (a.variables()[k].pose2.t - b.variables()[k].pose2.t).squaredNorm();
  }
  return std::sqrt(s / a.variables().size());
}

}  // namespace

TEST(Robust, IntelWithFalseLoopClosures) {
  gs::PoseGraph clean = gs::readG2o(kData + "intel.g2o");
  ASSERT_EQ(clean.variables().size(), 943u);
  gs::Optimizer().optimize(clean);

  gs::PoseGraph bad = gs::readG2o(kData + "intel.g2o");
  const std::size_t first_outlier = addFalseLoopClosures(bad, 100, 7);

  gs::PoseGraph plain = bad;
  gs::Optimizer().optimize(plain);
  const double plain_err = rmsDiff(plain, clean);
  EXPECT_GT(plain_err, 1.0);  // least squares is wrecked (metres)

  gs::PoseGraph dcs = bad;
  dcs.setRobustKernelAll(gs::RobustKernel::parse("dcs:1"));
  const auto ds = gs::Optimizer().optimize(dcs);
  EXPECT_TRUE(ds.converged) << ds.termination;
  // DCS keeps the outliers' pull small but not zero (a few centimetres on a 40 m map).
  EXPECT_LT(rmsDiff(dcs, clean), 0.1) << "plain " << plain_err;

  gs::PoseGraph gnc = bad;
  gs::Optimizer opt;
  const auto gsum = gs::optimizeGnc(gnc, opt);
  EXPECT_LT(rmsDiff(gnc, clean), 0.01) << "plain " << plain_err;
  // Every injected closure is rejected; the genuine loop closures are kept.
  std::size_t kept_outliers = 0, dropped_inliers = 0;
  for (std::size_t k = 0; k < gsum.weights.size(); ++k) {
    if (k >= first_outlier && gsum.weights[k] >= 0.5) ++kept_outliers;
    if (k < first_outlier && gsum.weights[k] < 0.5) ++dropped_inliers;
  }
  EXPECT_EQ(kept_outliers, 0u);
  EXPECT_LT(dropped_inliers, 20u);
  // GNC re-weights only: all its inner optimizations share one symbolic analysis.
  EXPECT_EQ(gsum.last.symbolic_analyses, 1);

  // The truncated-least-squares surrogate (mu increasing until the weights are binary) does the same here.
  gs::PoseGraph tls = bad;
  gs::Optimizer opt_tls;
  gs::GncOptions go;
  go.surrogate = gs::GncSurrogate::kTruncatedLeastSquares;
  const auto tsum = gs::optimizeGnc(tls, opt_tls, go);
  EXPECT_LT(rmsDiff(tls, clean), 0.01) << "plain " << plain_err;
  kept_outliers = dropped_inliers = 0;
  for (std::size_t k = 0; k < tsum.weights.size(); ++k) {
    if (k >= first_outlier && tsum.weights[k] >= 0.5) ++kept_outliers;
    if (k < first_outlier && tsum.weights[k] < 0.5) ++dropped_inliers;
  }
  EXPECT_EQ(kept_outliers, 0u);
  EXPECT_LT(dropped_inliers, 20u);
}
