#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "cairn/copa_map/initialization.hpp"

using namespace cairn::copa_map;

TEST(CopaInit, NudftAndReconstructionRecoverAPlantedCosine) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 200.0);
  Eigen::VectorXd t(300), y(300);
  for (int j = 0; j < 300; ++j) {
    t[j] = u(rng);  // non-uniform sampling
    y[j] = 4.0 + 2.0 * std::cos(2 * M_PI * t[j] / 12.0 + 0.7);
  }
  const std::vector<double> periods{8.0, 12.0, 20.0};
  const auto xi = nudft(t, y, periods, y.mean());
  EXPECT_GT(std::abs(xi[1]), 5 * std::abs(xi[0]));
  EXPECT_NEAR(2 * std::abs(xi[1]), 2.0, 0.25);
  const Eigen::VectorXd rec = fourierReconstruct(t, y.mean(), {xi[1]}, {12.0});
  EXPECT_LT(std::sqrt((rec - y).squaredNorm() / 300), 0.3);
}

// §4.3.3: on ATC the initialization found 12 h and 6 h periods. Here they are planted in per-cell rates (with
// random amplitudes, noise and irregular observation times as from a moving robot) and must be recovered.
TEST(CopaInit, Algorithm41RecoversPlanted12hAnd6hPeriods) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::uniform_real_distribution<double> amp(0.5, 2.0), obs(0.0, 1.0);
  std::vector<Eigen::Vector4d> rows;
  for (int cx = 0; cx < 6; ++cx)
    for (int cy = 0; cy < 4; ++cy) {
      const double a = amp(rng);
      for (int t = 0; t < 240; ++t) {
        if (obs(rng) < 0.35) continue;  // cell not visited in this bin
        const double x1 = cx * 5.0 + 2.0, x2 = cy * 5.0 + 2.0;
        const double rate =
            a * (5.0 + 3.0 * std::cos(2 * M_PI * t / 12.0) + 1.5 * std::cos(2 * M_PI * t / 6.0 + 1.0)) + noise(rng);
        rows.emplace_back(x1, x2, t, std::max(0.0, rate));
      }
    }
  Eigen::MatrixXd X(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::VectorXd y(X.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    X.row(i) = rows[static_cast<std::size_t>(i)].head<3>();
    y[i] = rows[static_cast<std::size_t>(i)][3];
  }
  PeriodInitConfig cfg;
  cfg.period_max = 48.0;
  cfg.seed = 3;
  const PeriodInitResult r = initializePeriods(X, y, Eigen::VectorXd(), cfg);
  ASSERT_EQ(r.periods.size(), 2u);
  EXPECT_NEAR(r.periods[0], 12.0, 0.3);
  EXPECT_NEAR(r.periods[1], 6.0, 0.3);
  EXPECT_NEAR(r.variances[0], 0.95, 1e-12);  // normalized to σ²_max
  EXPECT_NEAR(r.variances[1] / r.variances[0], 0.5, 0.12);  // amplitude ratio 1.5 / 3
  EXPECT_EQ(r.chosen_b.size(), 10u);  // Λ = 10 series
}

TEST(CopaInit, WeightedKMeansFollowsTheWeights) {
  // Two groups; the heavy points of group B pull its centre.
  Eigen::MatrixXd P(6, 2);
  P << 0, 0, 1, 0, 0, 1, 10, 10, 11, 10, 14, 10;
  Eigen::VectorXd w(6);
  w << 1, 1, 1, 1, 1, 8;
  const KMeansResult r = weightedKMeans(P, w, 2, 50, 1);
  Eigen::RowVector2d cb = r.centers.row(r.labels[3]);
  EXPECT_NEAR(cb[0], (10 + 11 + 14 * 8) / 10.0, 1e-9);
  EXPECT_EQ(r.labels[0], r.labels[1]);
  EXPECT_NE(r.labels[0], r.labels[3]);
  EXPECT_THROW(weightedKMeans(P, -w, 2, 10, 1), std::invalid_argument);
}

TEST(CopaInit, InducingPointsCountAndDurationWeighting) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  Eigen::MatrixXd X(1000, 3);
  Eigen::VectorXd d(1000);
  for (int i = 0; i < 1000; ++i) {
    X.row(i) << u(rng), u(rng), u(rng);
    d[i] = X(i, 0) < 5.0 ? 100.0 : 1.0;  // left half observed much longer
  }
  const Eigen::MatrixXd Z = initializeInducing(X, d, 0.02, 50, 4);
  ASSERT_EQ(Z.rows(), 20);  // m = ⌊0.02 n⌋
  const auto left = (Z.col(0).array() < 5.0).count();
  EXPECT_GE(left, 13);  // most inducing points where Δ is large
  EXPECT_THROW(initializeInducing(X, d, 0.0, 10, 1), std::invalid_argument);
}

TEST(CopaInit, BadCandidatePeriodStepsThrowInsteadOfLooping) {
  Eigen::MatrixXd X(12, 3);
  Eigen::VectorXd y(12);
  for (int t = 0; t < 12; ++t) {
    X.row(t) << 1.0, 1.0, t;
    y[t] = 1.0 + t % 3;
  }
  PeriodInitConfig cfg;
  cfg.period_step = 0.0;  // p += 0 never reached period_max
  EXPECT_THROW(initializePeriods(X, y, Eigen::VectorXd(), cfg), std::invalid_argument);
  cfg.period_step = 1e-9;  // 5e9 candidates
  EXPECT_THROW(initializePeriods(X, y, Eigen::VectorXd(), cfg), std::invalid_argument);
  cfg.period_min = 1e12;  // p + step == p in doubles: accumulation never advanced
  cfg.period_step = 1e-6;
  EXPECT_NO_THROW(initializePeriods(X, y, Eigen::VectorXd(), cfg));
}
