#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <random>

#include "cairn/copa_map/cpu_dispatch.hpp"
#include "cairn/copa_map/kernels.hpp"
#include "cairn/copa_map/svgp.hpp"

using namespace cairn::copa_map;

namespace {

Eigen::MatrixXd randomInputs(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> ux(0.0, 6.0), ut(0.0, 30.0);
  Eigen::MatrixXd X(n, 3);
  for (int i = 0; i < n; ++i) X.row(i) << ux(rng), ux(rng), ut(rng);
  return X;
}

std::unique_ptr<Kernel> stKernel() {
  return std::make_unique<SpatioTemporalKernel>(
      1.7, 2.3, std::vector<PeriodicComponent>{{0.8, 12.0, 0.9}, {0.3, 6.0, 1.3}});
}

// n standard-normal targets.
Eigen::VectorXd normalTargets(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) y[i] = nd(rng);
  return y;
}

// Random q(u) so that all gradient terms are exercised.
void randomizeQ(LatentGp& lat, std::mt19937_64& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  const auto m = lat.Z.rows();
  for (Eigen::Index i = 0; i < m; ++i) {
    lat.mu[i] = 0.5 * nd(rng);
    for (Eigen::Index j = 0; j < i; ++j) lat.L(i, j) = 0.1 * nd(rng);
    lat.L(i, i) = 0.3 + 0.2 * std::abs(nd(rng));
  }
}

SvgpModel heteroModel(std::mt19937_64& rng, int m) {
  std::vector<LatentGp> lat;
  lat.emplace_back(stKernel(), randomInputs(m, rng));
  lat.emplace_back(std::make_unique<RbfKernel>(0.7, Eigen::Vector3d(2.0, 3.0, 10.0)), randomInputs(m, rng));
  for (auto& l : lat) randomizeQ(l, rng);
  return SvgpModel(std::move(lat), std::make_unique<HeteroscedasticGaussianLikelihood>(20), 1e-6);
}

}  // namespace

TEST(CopaKernels, AnalyticGradientsMatchFiniteDifferences) {
  std::mt19937_64 rng(3);
  const Eigen::MatrixXd X1 = randomInputs(7, rng), X2 = randomInputs(5, rng);
  Eigen::MatrixXd G = Eigen::MatrixXd::Random(7, 5);
  std::vector<std::unique_ptr<Kernel>> ks;
  ks.push_back(stKernel());
  ks.push_back(std::make_unique<RbfKernel>(0.7, Eigen::Vector3d(2.0, 3.0, 10.0)));
  for (auto& k : ks) {
    const Eigen::VectorXd g = k->gradK(X1, X2, G);
    const Eigen::VectorXd p0 = k->params();
    for (int p = 0; p < k->numParams(); ++p) {
      const double h = 1e-6;
      Eigen::VectorXd pp = p0, pm = p0;
      pp[p] += h;
      pm[p] -= h;
      k->setParams(pp);
      const double fp = (G.array() * k->K(X1, X2).array()).sum();
      k->setParams(pm);
      const double fm = (G.array() * k->K(X1, X2).array()).sum();
      k->setParams(p0);
      EXPECT_NEAR(g[p], (fp - fm) / (2 * h), 1e-6 * (1 + std::abs(g[p]))) << k->type() << " param " << p;
    }
    // Kdiag equals the diagonal of K.
    EXPECT_NEAR((k->K(X1, X1).diagonal() - k->Kdiag(X1)).norm(), 0.0, 1e-12);
  }
}

// Gridded inputs (cell centres on a 0.5 m grid, integer time bins, like the gridifier's output and the ATC files):
// the value-table path of SpatioTemporalKernel must give exactly the direct per-entry K and the same gradK up to
// rounding, also on the lower-triangular weights of the K(Z, Z) gradient; continuous inputs keep the direct path.
TEST(CopaKernels, ValueTablesEqualTheDirectEvaluationOnGriddedInputs) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> cell(0, 7), bin(0, 29);
  auto grid = [&](int n) {
    Eigen::MatrixXd X(n, 3);
    for (int i = 0; i < n; ++i) X.row(i) << 0.25 + 0.5 * cell(rng), -1.25 + 0.5 * cell(rng), bin(rng);
    return X;
  };
  const Eigen::MatrixXd X = grid(400), Z = grid(150);
  auto tab = stKernel(), direct = stKernel();
  static_cast<SpatioTemporalKernel&>(*direct).use_value_tables = false;
  ASSERT_TRUE(SpatioTemporalKernel::valueTablesApply(X, Z));
  ASSERT_TRUE(SpatioTemporalKernel::valueTablesApply(Z, Z));
  EXPECT_FALSE(SpatioTemporalKernel::valueTablesApply(randomInputs(400, rng), randomInputs(150, rng)));
  const Eigen::MatrixXd K1 = tab->K(X, Z), K0 = direct->K(X, Z);
  ASSERT_EQ(K1.rows(), 400);
  EXPECT_EQ((K1 - K0).cwiseAbs().maxCoeff(), 0.0);  // bit-identical
  EXPECT_EQ((tab->K(Z, Z) - direct->K(Z, Z)).cwiseAbs().maxCoeff(), 0.0);
  std::normal_distribution<double> nd(0.0, 1.0);
  Eigen::MatrixXd G(400, 150), Gzz = Eigen::MatrixXd::Zero(150, 150);
  for (Eigen::Index j = 0; j < G.cols(); ++j)
    for (Eigen::Index i = 0; i < G.rows(); ++i) G(i, j) = nd(rng);
  Gzz.triangularView<Eigen::Lower>() = G.topRows(150);
  for (const Eigen::MatrixXd* g : {&G, &Gzz}) {
    const Eigen::MatrixXd& A = g == &G ? X : Z;
    const Eigen::VectorXd g1 = tab->gradK(A, Z, *g), g0 = direct->gradK(A, Z, *g);
    ASSERT_EQ(g1.size(), 8);
    for (Eigen::Index p = 0; p < g0.size(); ++p) EXPECT_NEAR(g1[p], g0[p], 1e-11 * (1.0 + std::abs(g0[p]))) << p;
  }
  // A changed parameter changes the tables (nothing is cached across calls).
  Eigen::VectorXd prm = tab->params();
  prm[0] += 0.3;
  prm[4] -= 0.2;
  tab->setParams(prm);
  direct->setParams(prm);
  EXPECT_EQ((tab->K(X, Z) - direct->K(X, Z)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(CopaKernels, MaternAndPeriodicValues) {
  // Matérn-5/2 at r = |d|/l = 1: (1 + √5 + 5/3) e^{-√5}; periodic at Δt = period: full correlation.
  SpatioTemporalKernel k(2.0, 1.0, {{0.5, 12.0, 1.0}});
  Eigen::MatrixXd a(1, 3), b(1, 3);
  a << 0, 0, 0;
  b << 2.0, 0, 12.0;
  const double expect = (1 + std::sqrt(5.0) + 5.0 / 3.0) * std::exp(-std::sqrt(5.0)) * 0.5;
  EXPECT_NEAR(k.K(a, b)(0, 0), expect, 1e-12);
  b << 0, 0, 3.0;  // quarter period: sin² = 0.5
  EXPECT_NEAR(k.K(a, b)(0, 0), 0.5 * std::exp(-0.25), 1e-12);
}

TEST(CopaSvgp, GaussHermiteIntegratesPolynomialsExactly) {
  Eigen::VectorXd x, w;
  gaussHermite(10, x, w);
  EXPECT_NEAR(w.sum(), std::sqrt(M_PI), 1e-12);
  EXPECT_NEAR((w.array() * x.array().square()).sum(), std::sqrt(M_PI) / 2.0, 1e-12);
  EXPECT_NEAR((w.array() * x.array().pow(4)).sum(), 3.0 * std::sqrt(M_PI) / 4.0, 1e-11);
}

// With Z = X, a Gaussian likelihood and fixed hyperparameters, one full-batch natural-gradient step with γ = 1
// gives the exact posterior; predictions equal exact GP regression (eqs. 4.2-4.3) and the ELBO equals the log
// marginal likelihood (eq. 4.4).
TEST(CopaSvgp, FullRankSvgpEqualsExactGpRegression) {
  std::mt19937_64 rng(11);
  const int n = 40;
  const Eigen::MatrixXd X = randomInputs(n, rng);
  Eigen::VectorXd y(n);
  std::normal_distribution<double> nd(0.0, 0.3);
  for (int i = 0; i < n; ++i) y[i] = std::sin(X(i, 0)) + std::cos(2 * M_PI * X(i, 2) / 12.0) + nd(rng);
  const double noise = 0.09;
  auto kernel = stKernel();
  std::vector<LatentGp> lat;
  lat.emplace_back(kernel->clone(), X);
  SvgpModel model(std::move(lat), std::make_unique<GaussianLikelihood>(noise), 1e-9);
  const auto ev = model.evaluate(X, y, 1.0, false);
  EXPECT_GT(model.naturalGradientStep(0, ev, 1.0, 1.0), 0.99);

  const Eigen::MatrixXd Xs = randomInputs(15, rng);
  Eigen::MatrixXd Kxx = kernel->K(X, X);
  Kxx.diagonal().array() += noise;
  Eigen::LLT<Eigen::MatrixXd> llt(Kxx);
  const Eigen::MatrixXd Ksx = kernel->K(Xs, X);
  const Eigen::VectorXd mean = Ksx * llt.solve(y);
  const Eigen::VectorXd var =
      kernel->Kdiag(Xs) - (Ksx.array() * llt.solve(Ksx.transpose()).transpose().array()).rowwise().sum().matrix();
  const LatentMoments q = model.latentMoments(0, Xs);
  for (int i = 0; i < Xs.rows(); ++i) {
    EXPECT_NEAR(q.m[i], mean[i], 1e-5);
    EXPECT_NEAR(q.v[i], var[i], 1e-5);
  }
  const double logml = -0.5 * n * std::log(2 * M_PI) -
                       Eigen::MatrixXd(llt.matrixL()).diagonal().array().log().sum() - 0.5 * y.dot(llt.solve(y));
  EXPECT_NEAR(model.evaluate(X, y, 1.0, false).elbo, logml, 1e-4);
}

// Analytic ELBO gradients (hyperparameters of both latents, and μ) vs central finite differences.
TEST(CopaSvgp, ElboGradientsMatchFiniteDifferences) {
  std::mt19937_64 rng(5);
  SvgpModel model = heteroModel(rng, 9);
  const Eigen::MatrixXd X = randomInputs(60, rng);
  Eigen::VectorXd y(60);
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int i = 0; i < 60; ++i) y[i] = 0.5 * std::sin(X(i, 0)) + 0.7 * nd(rng);
  const double scale = 3.0;
  const auto ev = model.evaluate(X, y, scale, true);
  const Eigen::VectorXd p0 = model.hyperParams();
  ASSERT_EQ(ev.hyper_grad.size(), p0.size());
  for (int p = 0; p < p0.size(); ++p) {
    const double h = 1e-5;
    Eigen::VectorXd pp = p0, pm = p0;
    pp[p] += h;
    pm[p] -= h;
    model.setHyperParams(pp);
    const double fp = model.evaluate(X, y, scale, false).elbo;
    model.setHyperParams(pm);
    const double fm = model.evaluate(X, y, scale, false).elbo;
    model.setHyperParams(p0);
    const double fd = (fp - fm) / (2 * h);
    EXPECT_NEAR(ev.hyper_grad[p], fd, 2e-4 * (1 + std::abs(fd))) << "hyperparameter " << p;
  }
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 9; j += 2) {
      const double h = 1e-5;
      model.latents()[k].mu[j] += h;
      const double fp = model.evaluate(X, y, scale, false).elbo;
      model.latents()[k].mu[j] -= 2 * h;
      const double fm = model.evaluate(X, y, scale, false).elbo;
      model.latents()[k].mu[j] += h;
      const double fd = (fp - fm) / (2 * h);
      EXPECT_NEAR(ev.latent[k].grad_mu[j], fd, 2e-4 * (1 + std::abs(fd))) << "latent " << k << " mu " << j;
    }
  }
}

// Heteroscedastic data: variance grows with x1. Training must raise the ELBO, fit the mean, and the learnt
// noise (predictive std) must be larger on the noisy side.
TEST(CopaSvgp, TrainingLearnsHeteroscedasticNoise) {
  std::mt19937_64 rng(21);
  const int n = 600;
  Eigen::MatrixXd X(n, 3);
  Eigen::VectorXd y(n), f(n);
  std::uniform_real_distribution<double> ux(0.0, 10.0), ut(0.0, 48.0);
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    X.row(i) << ux(rng), 1.0, ut(rng);
    f[i] = std::sin(0.6 * X(i, 0)) + 0.8 * std::cos(2 * M_PI * X(i, 2) / 12.0);
    y[i] = f[i] + (X(i, 0) < 5 ? 0.05 : 0.8) * nd(rng);
  }
  Eigen::MatrixXd Z(40, 3);
  for (int j = 0; j < 40; ++j) Z.row(j) << (j % 10) + 0.5, 1.0, (j / 10) * 12.0 + 3.0;
  std::vector<LatentGp> lat;
  lat.emplace_back(std::make_unique<SpatioTemporalKernel>(2.0, 5.0, std::vector<PeriodicComponent>{{1.0, 12.0, 1.0}}), Z);
  lat.emplace_back(std::make_unique<RbfKernel>(1.0, Eigen::Vector3d(3.0, 5.0, 50.0)), Z);
  SvgpModel model(std::move(lat), std::make_unique<HeteroscedasticGaussianLikelihood>(20), 1e-6);
  const double elbo0 = model.evaluate(X, y, 1.0, false).elbo;
  TrainConfig cfg;
  cfg.batch_size = 200;
  cfg.max_iterations = 300;
  cfg.natgrad_gamma_start = cfg.natgrad_gamma_end = 0.2;
  cfg.adam_lr_start = 0.03;
  cfg.adam_lr_end = 0.01;
  cfg.tolerance = 1e-5;
  cfg.seed = 4;
  const TrainReport rep = trainSvgp(model, X, y, cfg);
  EXPECT_FALSE(rep.diverged) << rep.message;
  const double elbo1 = model.evaluate(X, y, 1.0, false).elbo;
  EXPECT_GT(elbo1, elbo0 + 100.0);
  Eigen::VectorXd mean, var;
  model.predictY(X, mean, var);
  const double rmse = std::sqrt((mean - f).squaredNorm() / n);
  EXPECT_LT(rmse, 0.2);
  double var_lo = 0, var_hi = 0;
  int nlo = 0, nhi = 0;
  for (int i = 0; i < n; ++i) (X(i, 0) < 5 ? (var_lo += var[i], ++nlo) : (var_hi += var[i], ++nhi));
  EXPECT_GT(var_hi / nhi, 4.0 * var_lo / nlo);
}

TEST(CopaSvgp, NanDataIsRejectedAndDivergenceKeepsLastGoodModel) {
  std::mt19937_64 rng(8);
  SvgpModel model = heteroModel(rng, 6);
  Eigen::MatrixXd X = randomInputs(20, rng);
  Eigen::VectorXd y = Eigen::VectorXd::Ones(20);
  y[3] = std::nan("");
  TrainConfig cfg;
  EXPECT_THROW(trainSvgp(model, X, y, cfg), std::invalid_argument);
  EXPECT_THROW(trainSvgp(model, Eigen::MatrixXd(0, 3), Eigen::VectorXd(0), cfg), std::invalid_argument);
  // Absurd data scale with an absurd learning rate: either it trains or it stops cleanly with finite parameters.
  y.setConstant(1e200);
  cfg.adam_lr_start = cfg.adam_lr_end = 50.0;
  cfg.max_iterations = 20;
  const TrainReport rep = trainSvgp(model, X, y, cfg);
  EXPECT_TRUE(rep.diverged);
  EXPECT_TRUE(model.hyperParams().allFinite());
  for (const auto& l : model.latents()) EXPECT_TRUE(l.mu.allFinite() && l.L.allFinite());
}

TEST(CopaSvgp, InducingInputGradientsMatchFiniteDifferences) {
  std::mt19937_64 rng(11);
  SvgpModel model = heteroModel(rng, 6);
  const Eigen::MatrixXd X = randomInputs(15, rng);
  std::normal_distribution<double> nd(0.0, 1.0);
  Eigen::VectorXd y(15);
  for (int i = 0; i < 15; ++i) y[i] = nd(rng);
  const double scale = 2.5;
  const ElboEvaluation ev = model.evaluate(X, y, scale, false, true);
  ASSERT_EQ(ev.z_grad.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(ev.z_grad[k].rows(), 6);
    double norm = 0;
    for (int i = 0; i < 6; ++i)
      for (int d = 0; d < 3; ++d) {
        const double h = 1e-5, z0 = model.latents()[k].Z(i, d);
        model.latents()[k].Z(i, d) = z0 + h;
        const double fp = model.evaluate(X, y, scale, false).elbo;
        model.latents()[k].Z(i, d) = z0 - h;
        const double fm = model.evaluate(X, y, scale, false).elbo;
        model.latents()[k].Z(i, d) = z0;
        const double fd = (fp - fm) / (2 * h);
        EXPECT_NEAR(ev.z_grad[k](i, d), fd, 1e-5 * (1 + std::abs(fd))) << "latent " << k << " z " << i << "," << d;
        norm += fd * fd;
      }
    EXPECT_GT(norm, 1e-6);  // the check is not vacuous
  }
  // The kernel's input gradients on their own (both arguments), including a symmetric K(Z, Z) use.
  const Eigen::MatrixXd X1 = randomInputs(5, rng), X2 = randomInputs(4, rng);
  const Eigen::MatrixXd G = Eigen::MatrixXd::Random(5, 4);
  for (const auto& lat : model.latents()) {
    Eigen::MatrixXd d1, d2;
    lat.kernel->gradInputs(X1, X2, G, &d1, &d2);
    for (int i = 0; i < 5; ++i)
      for (int d = 0; d < 3; ++d) {
        Eigen::MatrixXd Xp = X1, Xm = X1;
        Xp(i, d) += 1e-6;
        Xm(i, d) -= 1e-6;
        const double fd = ((G.array() * lat.kernel->K(Xp, X2).array()).sum() -
                           (G.array() * lat.kernel->K(Xm, X2).array()).sum()) / 2e-6;
        EXPECT_NEAR(d1(i, d), fd, 1e-6 * (1 + std::abs(fd)));
      }
    for (int j = 0; j < 4; ++j)
      for (int d = 0; d < 3; ++d) {
        Eigen::MatrixXd Xp = X2, Xm = X2;
        Xp(j, d) += 1e-6;
        Xm(j, d) -= 1e-6;
        const double fd = ((G.array() * lat.kernel->K(X1, Xp).array()).sum() -
                           (G.array() * lat.kernel->K(X1, Xm).array()).sum()) / 2e-6;
        EXPECT_NEAR(d2(j, d), fd, 1e-6 * (1 + std::abs(fd)));
      }
  }
}

TEST(CopaSvgp, TrainingTheInducingInputsRaisesTheElbo) {
  // Inducing points start bunched in one corner; with Z trained the bound ends higher than with Z fixed.
  std::mt19937_64 rng(5);
  const Eigen::MatrixXd X = randomInputs(300, rng);
  Eigen::VectorXd y(300);
  for (int i = 0; i < 300; ++i) y[i] = std::sin(X(i, 0)) + 0.5 * std::cos(X(i, 1)) + 0.05 * std::sin(X(i, 2));
  auto build = [&] {
    std::mt19937_64 r2(7);
    Eigen::MatrixXd Z = 0.3 * randomInputs(12, r2);
    std::vector<LatentGp> lat;
    lat.emplace_back(stKernel(), Z);
    lat.emplace_back(std::make_unique<RbfKernel>(0.5, Eigen::Vector3d(3.0, 3.0, 20.0)), Z.topRows(4));
    return SvgpModel(std::move(lat), std::make_unique<HeteroscedasticGaussianLikelihood>(10), 1e-6);
  };
  TrainConfig tc;
  tc.batch_size = 300;
  tc.max_iterations = 150;
  tc.natgrad_gamma_start = tc.natgrad_gamma_end = 0.5;
  tc.train_hyper = false;
  tc.tolerance = 0;
  SvgpModel fixed = build(), moved = build();
  trainSvgp(fixed, X, y, tc);
  tc.train_inducing = true;
  tc.inducing_lr = 0.05;
  trainSvgp(moved, X, y, tc);
  EXPECT_GT((moved.latents()[0].Z - fixed.latents()[0].Z).norm(), 0.5);
  EXPECT_GT(moved.evaluate(X, y, 1.0, false).elbo, fixed.evaluate(X, y, 1.0, false).elbo + 1.0);
}

// The run-time dispatched GEMM variants (cpu_dispatch.hpp) give the same ELBO, gradients and natural-gradient
// step as the portable one, up to floating-point reassociation (FMA, wider vectors). m = 300 > 2 column blocks,
// so the blocked triangular products and the Gram matrix go through the dispatched GEMM too.
TEST(CopaSvgp, GemmVariantsAndBatchSplitAgreeWithThePortableSerialOne) {
  const std::string saved = activeGemmKernel();
  std::mt19937_64 rng(11);
  const SvgpModel base = heteroModel(rng, 300);
  const Eigen::MatrixXd X = randomInputs(400, rng);
  const Eigen::VectorXd y = normalTargets(400, rng);
  auto run = [&](const std::string& variant, ElboEvaluation& ev, SvgpModel& stepped) {
    selectGemmKernel(variant);
    stepped = base;
    ev = stepped.evaluate(X, y, 3.0, true, true);
    stepped.naturalGradientStep(0, ev, 3.0, 0.5);
  };
  ElboEvaluation ref;
  SvgpModel ref_model;
  run("generic", ref, ref_model);
  const auto variants = availableGemmKernels();
  ASSERT_EQ(variants.front(), "generic");
  for (const auto& v : variants) {
    ElboEvaluation ev;
    SvgpModel m;
    run(v, ev, m);
    EXPECT_NEAR(ev.elbo, ref.elbo, 1e-9 * std::abs(ref.elbo)) << v;
    EXPECT_LE((ev.hyper_grad - ref.hyper_grad).norm(), 1e-8 * ref.hyper_grad.norm()) << v;
    EXPECT_LE((ev.z_grad[0] - ref.z_grad[0]).norm(), 1e-8 * ref.z_grad[0].norm()) << v;
    EXPECT_LE((ev.latent[0].Q - ref.latent[0].Q).norm(), 1e-9 * ref.latent[0].Q.norm()) << v;
    EXPECT_LE((m.latents()[0].L - ref_model.latents()[0].L).norm(), 1e-8 * ref_model.latents()[0].L.norm()) << v;
  }
  EXPECT_THROW(selectGemmKernel("no-such-isa"), std::invalid_argument);
  selectGemmKernel(saved);

  // evaluate() splits the batch into one block of rows per core; one block gives the same sums.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const ElboEvaluation one = base.evaluate(X, y, 3.0, true, true);
  omp_set_num_threads(2);
  const ElboEvaluation two = base.evaluate(X, y, 3.0, true, true);
  omp_set_num_threads(threads);
  EXPECT_NEAR(one.elbo, two.elbo, 1e-10 * std::abs(one.elbo));
  // (Latent 1's Z gradient is not compared: with 300 random inducing inputs its K_uu is so ill-conditioned that
  // the gradient is a sum of huge cancelling terms, and any change of summation order moves it.)
  EXPECT_LE((one.hyper_grad - two.hyper_grad).norm(), 1e-8 * one.hyper_grad.norm());
  EXPECT_LE((one.z_grad[0] - two.z_grad[0]).norm(), 1e-8 * one.z_grad[0].norm());
  EXPECT_LE((one.latent[1].Q - two.latent[1].Q).norm(), 1e-10 * one.latent[1].Q.norm());
  EXPECT_LE((one.latent[0].b - two.latent[0].b).norm(), 1e-10 * one.latent[0].b.norm());
}

// Mixed precision (SvgpModel::setMixedPrecision: single-precision A L and Aᵀ diag(∂E/∂v) A, double everything
// else) against the double path on the same model and batch, including latent 1's ill-conditioned K_uu (300 random
// inducing inputs under an RBF kernel). Tolerances (relative): ELBO 1e-6, Q and b 1e-5 (float rounding of A,
// ~6e-8 per entry, summed in chunks of 256 rows), hyperparameter gradient 1e-4; after a natural-gradient step
// (which must be taken in full: the precision stays positive definite) q(f) at the batch inputs (mean and
// variance) 5e-3 and ≤ 1/10 of what another mini-batch changes, the ELBO 1e-6. A short training run reaches the
// same epoch ELBO to 1e-4 nats per point.
TEST(CopaSvgp, MixedPrecisionAgreesWithTheDoublePath) {
  std::mt19937_64 rng(13);
  const SvgpModel base = heteroModel(rng, 300);
  const Eigen::MatrixXd X = randomInputs(700, rng);
  const Eigen::VectorXd y = normalTargets(700, rng);
  SvgpModel dbl = base, mix = base;
  mix.setMixedPrecision(true);
  ASSERT_TRUE(mix.mixedPrecision());
  const ElboEvaluation d = dbl.evaluate(X, y, 3.0, true);
  const ElboEvaluation f = mix.evaluate(X, y, 3.0, true);
  EXPECT_NEAR(f.elbo, d.elbo, 1e-6 * std::abs(d.elbo));
  EXPECT_LE((f.hyper_grad - d.hyper_grad).norm(), 1e-4 * d.hyper_grad.norm());
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_LE((f.latent[k].Q - d.latent[k].Q).norm(), 1e-5 * d.latent[k].Q.norm()) << k;
    EXPECT_LE((f.latent[k].b - d.latent[k].b).norm(), 1e-5 * d.latent[k].b.norm()) << k;
  }
  EXPECT_GT((f.latent[0].Q - d.latent[0].Q).norm(), 0.0);  // the single-precision path was taken
  // The same step in double from another mini-batch of the same size and distribution: the sampling noise that
  // stochastic natural-gradient steps live with anyway.
  SvgpModel other = base;
  const Eigen::MatrixXd X2 = randomInputs(700, rng);
  const Eigen::VectorXd y2 = normalTargets(700, rng);
  const ElboEvaluation d2 = other.evaluate(X2, y2, 3.0, false);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(dbl.naturalGradientStep(k, d, 3.0, 0.5), 0.5);
    EXPECT_EQ(mix.naturalGradientStep(k, f, 3.0, 0.5), 0.5) << k;
    other.naturalGradientStep(k, d2, 3.0, 0.5);
    // Compared in function space (q(f) at the batch inputs). K_uu here is far worse conditioned than ATC's
    // (random inputs, jitter 1e-6), and the float rounding of Q, though 1e-5 relative, is amplified by the
    // inverse of the new precision: measured 1.1e-3 (mean) and 2e-4 (variance) for latent 0 at this seed,
    // 4e-5 / 3e-8 with 80 inducing inputs. Bounds: 5e-3, and at most a tenth of the batch-to-batch change.
    const LatentMoments a = mix.latentMoments(k, X), b = dbl.latentMoments(k, X), c = other.latentMoments(k, X);
    EXPECT_LE((a.m - b.m).norm(), 5e-3 * b.m.norm()) << k;
    EXPECT_LE((a.v - b.v).norm(), 5e-3 * b.v.norm()) << k;
    EXPECT_LE((a.m - b.m).norm(), 0.1 * (c.m - b.m).norm()) << k;
    EXPECT_LE((a.v - b.v).norm(), 0.1 * (c.v - b.v).norm()) << k;
  }
  EXPECT_NEAR(mix.evaluate(X, y, 3.0, false).elbo, dbl.evaluate(X, y, 3.0, false).elbo, 1e-6 * std::abs(d.elbo));
  // Training: the setting is applied for the run and the model's own flag restored.
  const Eigen::MatrixXd Xt = randomInputs(600, rng);
  const Eigen::VectorXd yt = Xt.col(0).array().sin().matrix() + 0.3 * normalTargets(600, rng);
  std::vector<LatentGp> lat;
  lat.emplace_back(stKernel(), randomInputs(60, rng));
  lat.emplace_back(std::make_unique<RbfKernel>(0.7, Eigen::Vector3d(2.0, 3.0, 10.0)), randomInputs(20, rng));
  const SvgpModel start(std::move(lat), std::make_unique<HeteroscedasticGaussianLikelihood>(20), 1e-6);
  TrainConfig tc;
  tc.batch_size = 200;
  tc.max_iterations = 60;
  tc.tolerance = 0;
  SvgpModel t_dbl = start, t_mix = start;
  const TrainReport r_dbl = trainSvgp(t_dbl, Xt, yt, tc);
  tc.mixed_precision = true;
  const TrainReport r_mix = trainSvgp(t_mix, Xt, yt, tc);
  EXPECT_FALSE(t_mix.mixedPrecision());
  ASSERT_EQ(r_mix.epoch_elbo.size(), r_dbl.epoch_elbo.size());
  EXPECT_NEAR(r_mix.final_elbo, r_dbl.final_elbo, 1e-4);
}

// Step-size schedules after the linear warm-up (TrainConfig::step_decay) and the patience of the convergence
// test: the γ of the last step follows the documented formula, and training stops only after `patience`
// consecutive epochs below the tolerance.
TEST(CopaSvgp, StepDecaySchedulesAndConvergencePatience) {
  std::mt19937_64 rng(5);
  const SvgpModel base = heteroModel(rng, 10);
  const Eigen::MatrixXd X = randomInputs(200, rng);
  Eigen::VectorXd y(200);
  for (int i = 0; i < 200; ++i) y[i] = std::sin(X(i, 0)) + 0.3 * std::cos(X(i, 1));
  TrainConfig tc;
  tc.batch_size = 50;  // 4 batches per epoch
  tc.max_iterations = 41;
  tc.natgrad_gamma_start = 0.4;
  tc.natgrad_gamma_end = 0.2;
  tc.decay_steps = 10;
  tc.tolerance = 0;
  tc.hyper_every = 2;

  SvgpModel m = base;
  TrainReport rep = trainSvgp(m, X, y, tc);
  EXPECT_DOUBLE_EQ(rep.final_gamma, 0.2);  // constant after the linear phase
  EXPECT_EQ(TrainConfig::StepDecay::Constant, stepDecayFromName(stepDecayName(tc.step_decay)));

  tc.step_decay = TrainConfig::StepDecay::InvSqrt;
  tc.decay_tau = 5;
  m = base;
  rep = trainSvgp(m, X, y, tc);
  ASSERT_FALSE(rep.diverged) << rep.message;
  EXPECT_DOUBLE_EQ(rep.final_gamma, 0.2 / std::sqrt(1.0 + (40 - 10) / 5.0));  // last step k = 40
  tc.decay_tau = 0;  // one epoch = 4 steps
  m = base;
  rep = trainSvgp(m, X, y, tc);
  EXPECT_DOUBLE_EQ(rep.final_gamma, 0.2 / std::sqrt(1.0 + (40 - 10) / 4.0));

  // Plateau: γ halves after every epoch whose mean ELBO is below the best one so far.
  tc.step_decay = stepDecayFromName("plateau");
  tc.natgrad_gamma_start = tc.natgrad_gamma_end = 1.0;  // large steps make the epoch ELBO stall and dip
  tc.adam_lr_start = tc.adam_lr_end = 0.3;
  tc.max_iterations = 81;  // 20 epochs; the last step (k = 80) comes after all 20 epoch tests
  m = base;
  rep = trainSvgp(m, X, y, tc);
  ASSERT_FALSE(rep.diverged) << rep.message;
  ASSERT_EQ(rep.epoch_elbo.size(), 20u);
  int stalls = 0;
  double best = rep.epoch_elbo[0];
  for (std::size_t e = 1; e < rep.epoch_elbo.size(); ++e) {
    stalls += rep.epoch_elbo[e] < best;
    best = std::max(best, rep.epoch_elbo[e]);
  }
  EXPECT_GT(stalls, 0);
  EXPECT_DOUBLE_EQ(rep.final_gamma, std::pow(0.5, stalls));
  EXPECT_THROW(stepDecayFromName("cosine"), std::invalid_argument);

  // Patience: with a tolerance every epoch passes, training stops after min_epochs - 1 + patience epochs.
  tc.step_decay = TrainConfig::StepDecay::Constant;
  tc.natgrad_gamma_start = tc.natgrad_gamma_end = 0.2;
  tc.tolerance = 1e3;
  tc.elbo_floor = 1.0;
  tc.min_epochs = 2;
  for (int patience : {1, 3}) {
    tc.patience = patience;
    m = base;
    rep = trainSvgp(m, X, y, tc);
    EXPECT_TRUE(rep.converged) << rep.message;
    EXPECT_EQ(rep.epochs, 1 + patience);
  }
  // A tolerance nothing meets never stops early.
  tc.tolerance = 1e-300;
  tc.elbo_floor = 0;
  m = base;
  rep = trainSvgp(m, X, y, tc);
  EXPECT_FALSE(rep.converged);
  EXPECT_EQ(rep.iterations, tc.max_iterations);
}

// Polyak–Ruppert tail averaging (TrainConfig::average_iterates): the returned q(u) has the mean natural
// parameters and the model the mean hyperparameters of the iterates of the last completed epoch and the partial
// one after it.
TEST(CopaSvgp, IterateAveragingReturnsTheMeanOfTheLastEpochsIterates) {
  std::mt19937_64 rng(6);
  SvgpModel model = heteroModel(rng, 8);
  const Eigen::MatrixXd X = randomInputs(200, rng);
  Eigen::VectorXd y(200);
  for (int i = 0; i < 200; ++i) y[i] = std::cos(X(i, 0)) - 0.2 * X(i, 1);
  TrainConfig tc;
  tc.batch_size = 50;  // 4 steps per epoch; epochs end after steps 3, 7, 11, 15
  tc.max_iterations = 18;
  tc.decay_steps = 2;
  tc.tolerance = 0;
  tc.hyper_every = 1;
  tc.natgrad_gamma_start = tc.natgrad_gamma_end = 0.3;
  tc.average_iterates = true;
  std::vector<Eigen::MatrixXd> lambda;
  std::vector<Eigen::VectorXd> theta, hyper;
  tc.progress = [&](int it, double, double) {
    if (it < 12) return;  // the window: steps 12..15 (last full epoch) and 16, 17
    const LatentGp& f = model.latents()[0];
    const Eigen::MatrixXd P = f.L.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(8, 8));
    lambda.push_back(P.transpose() * P);
    theta.push_back(lambda.back() * f.mu);
    hyper.push_back(model.hyperParams());
  };
  const TrainReport rep = trainSvgp(model, X, y, tc);
  ASSERT_FALSE(rep.diverged) << rep.message;
  ASSERT_EQ(rep.averaged_iterates, 6);
  ASSERT_EQ(lambda.size(), 6u);
  Eigen::MatrixXd lam = Eigen::MatrixXd::Zero(8, 8);
  Eigen::VectorXd th = Eigen::VectorXd::Zero(8), hy = Eigen::VectorXd::Zero(hyper[0].size());
  for (std::size_t i = 0; i < 6; ++i) {
    lam += lambda[i] / 6.0;
    th += theta[i] / 6.0;
    hy += hyper[i] / 6.0;
  }
  const LatentGp& f = model.latents()[0];
  const Eigen::MatrixXd S = f.L * f.L.transpose();
  EXPECT_LE((S * lam - Eigen::MatrixXd::Identity(8, 8)).norm(), 1e-7);
  EXPECT_LE((f.mu - lam.ldlt().solve(th)).norm(), 1e-7 * (1.0 + f.mu.norm()));
  EXPECT_LE((model.hyperParams() - hy).norm(), 1e-12 * (1.0 + hy.norm()));
  // The average differs from the last iterate (the run has not converged).
  EXPECT_GT((model.hyperParams() - hyper.back()).norm(), 1e-6);
}
