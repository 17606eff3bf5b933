// The reduced CoPA-Map configuration on the moving-robot ATC split (issue 7, "a reduced configuration that trains
// in <= 2 minutes and loses <= 5 % NRMSE, used by CI"): the authors' training split seen by the simulated moving
// robot (76,456 cells), every 4th of their inducing points, a fixed number of mini-batches (reducedTrainConfig:
// deterministic, no time limit), scored on the full ground-truth test split
// (eq. 4.20). The bound is the issue's: at most 5 % above the NRMSE of the full configuration (m_f = 1,915,
// atcTrainConfig, converged by its ELBO criterion in 10 minutes on 2 cores) measured in docs/benchmarks.md
// (copa_map). Measured: reduced 0.8055 = 1.040 x full 0.7749 with the AVX-512, AVX2 and portable GEMM variants
// (other CPUs) alike, mixed precision as in atcTrainConfig. The test fails if training or the model breaks or the
// schedule loses its settling.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "cairn/copa_map/baselines.hpp"
#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/copa_map/metrics.hpp"

using namespace cairn::copa_map;

namespace {

// NRMSE of the full configuration (m_f = 1,915, converged after 819 batches = 21 epochs), docs/benchmarks.md.
constexpr double kFullNrmse = CAIRN_COPA_ATC_FULL_NRMSE;
constexpr int kReducedBatches = CAIRN_COPA_ATC_REDUCED_BATCHES;
constexpr double kAllowedRatio = 1.05;  // issue 7: "loses <= 5 % NRMSE"

std::string atcDir() {
  if (const char* env = std::getenv("CAIRN_COPA_ATC_DATA")) return env;
  return std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/people/atc_copa_map";
}

}  // namespace

TEST(CopaAtc, ReducedMovingRobotConfigurationStaysNearTheFullModel) {
  const std::string dir = atcDir();
  const std::string train_csv = dir + "/grid_atc_50cm_60min_train_xy.csv";
  if (!std::filesystem::exists(train_csv))
    GTEST_SKIP() << "ATC CoPA-Map split not found (" << train_csv
                 << "); set CAIRN_COPA_ATC_DATA to the folder with grid_atc_50cm_60min_{train,test}_xy.csv and "
                    "grid_atc_50cm_60min_train_z.csv";
  const GridData train = readGridCsv(train_csv);
  const GridData test = readGridCsv(dir + "/grid_atc_50cm_60min_test_xy.csv");
  const Eigen::MatrixXd Z = everyNthRow(readInducingCsv(dir + "/grid_atc_50cm_60min_train_z.csv"), 4);
  ASSERT_EQ(train.X.rows(), 76456);
  ASSERT_EQ(Z.rows(), 479);

  CopaMapConfig cfg;
  CopaMap cm = CopaMap::initialize(train.X, train.y, Eigen::VectorXd(), cfg, &Z);
  const TrainReport rep = cm.train(train.X, train.y, reducedTrainConfig(kReducedBatches));
  ASSERT_FALSE(rep.diverged) << rep.message;
  EXPECT_EQ(rep.iterations, kReducedBatches);  // fixed work, not a time limit

  const double e = nrmse(cm.predict(test.X).mean, test.y);
  MlBaseline ml(cfg.cell_size);
  ml.fit(train.X, train.y);
  const double e_ml = nrmse(ml.predict(test.X).mean, test.y);
  std::printf("reduced ATC (m_f = %ld, %d batches, %.1f s): NRMSE %.4f (full %.4f, bound %.4f), ML %.4f\n",
              (long)Z.rows(), rep.iterations, rep.seconds, e, kFullNrmse, kAllowedRatio * kFullNrmse, e_ml);
  EXPECT_LE(e, kAllowedRatio * kFullNrmse);
  EXPECT_LT(e, e_ml);  // and better than the per-cell ML baseline (Fig. 4.10)
}
