// Cost of one CoPA-Map training step on the ATC split (Stüde 2024, §4.2.5): CPU seconds and wall seconds per
// mini-batch at the authors' inducing points (m_f = 1,915 full, every 4th reduced), with and without the
// hyperparameter gradient, for the phases of a step (ELBO evaluation, natural-gradient steps). Used to measure
// the per-batch cost changes recorded in docs/benchmarks.md: every GEMM variant the CPU can run (portable
// "generic" = before, avx2/avx512 = run-time dispatch) is measured in the same run on the same batches.
// Per GEMM variant up to three numeric modes on the same batches: "direct" (per-entry kernel evaluation, double:
// the code before the kernel value tables), "double" (value tables, double) and "mixed" (value tables,
// single-precision A L and Aᵀ D A; SvgpModel::setMixedPrecision), with the mixed-vs-double differences of ELBO,
// Q and hyperparameter gradient on the first batch.
//   bench_copa_step [--data DIR] [--reduced] [--batch B] [--steps N] [--seed N] [--gemm a,b,...]
//                   [--modes direct,double,mixed]
#include <time.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/cpu_dispatch.hpp"
#include "cairn/copa_map/io.hpp"
#include "cairn/copa_map/kernels.hpp"

#include <cmath>

using namespace cairn::copa_map;

namespace {
double cpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double wallNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
struct Timer {
  double c0 = cpuNow(), w0 = wallNow();
  double cpu() const { return cpuNow() - c0; }
  double wall() const { return wallNow() - w0; }
};
}  // namespace

int main(int argc, char** argv) {
  std::string dir = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/people/atc_copa_map";
  bool reduced = false;
  int batch = 2000, steps = 6;
  unsigned long seed = 1;
  std::vector<std::string> variants = availableGemmKernels();
  std::vector<std::string> modes{"direct", "double", "mixed"};
  auto splitList = [](const std::string& list) {
    std::vector<std::string> out;
    for (std::size_t p = 0; p <= list.size();) {
      const std::size_t q = std::min(list.find(',', p), list.size());
      out.push_back(list.substr(p, q - p));
      p = q + 1;
    }
    return out;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) dir = argv[++i];
    else if (a == "--reduced") reduced = true;
    else if (a == "--batch" && i + 1 < argc) batch = std::atoi(argv[++i]);
    else if (a == "--steps" && i + 1 < argc) steps = std::atoi(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::strtoul(argv[++i], nullptr, 10);
    else if (a == "--gemm" && i + 1 < argc) variants = splitList(argv[++i]);
    else if (a == "--modes" && i + 1 < argc) modes = splitList(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: %s [--data DIR] [--reduced] [--batch B] [--steps N] [--seed N] [--gemm a,b] "
                   "[--modes direct,double,mixed]\n",
                   argv[0]);
      return 2;
    }
  }
  for (const std::string& mode : modes)
    if (mode != "direct" && mode != "double" && mode != "mixed") {
      std::fprintf(stderr, "cairn: --modes: unknown mode '%s' (direct, double, mixed)\n", mode.c_str());
      return 2;
    }
  try {
    const GridData train = readGridCsv(dir + "/grid_atc_50cm_60min_train_xy.csv");
    Eigen::MatrixXd Z = readInducingCsv(dir + "/grid_atc_50cm_60min_train_z.csv");
    if (reduced) {
      Eigen::MatrixXd Zr(Z.rows() / 4, 3);
      for (Eigen::Index i = 0; i < Zr.rows(); ++i) Zr.row(i) = Z.row(4 * i);
      Z = Zr;
    }
    CopaMapConfig cfg;
    cfg.seed = cfg.period_init.seed = seed;
    const CopaMap initial = CopaMap::initialize(train.X, train.y, Eigen::VectorXd(), cfg, &Z);
    const Eigen::VectorXd ys = (train.y.array() - initial.yMean()) / initial.yScale();
    // Mixed-vs-double agreement on the first batch (same parameters): relative differences.
    {
      CopaMap cm = initial;
      SvgpModel& model = cm.model();
      std::mt19937_64 rng(seed);
      std::uniform_int_distribution<Eigen::Index> pick(0, train.X.rows() - 1);
      Eigen::MatrixXd Xb(batch, 3);
      Eigen::VectorXd yb(batch);
      for (int i = 0; i < batch; ++i) {
        const Eigen::Index r = pick(rng);
        Xb.row(i) = train.X.row(r);
        yb[i] = ys[r];
      }
      const double scale = static_cast<double>(train.X.rows()) / batch;
      const ElboEvaluation d = model.evaluate(Xb, yb, scale, true);
      model.setMixedPrecision(true);
      const ElboEvaluation f = model.evaluate(Xb, yb, scale, true);
      std::printf("mixed vs double, first batch (%s): ELBO %.9g vs %.9g (rel. %.2e); hyper-gradient max rel. %.2e;",
                  activeGemmKernel().c_str(), f.elbo, d.elbo, std::abs(f.elbo - d.elbo) / std::abs(d.elbo),
                  (f.hyper_grad - d.hyper_grad).cwiseAbs().maxCoeff() / d.hyper_grad.cwiseAbs().maxCoeff());
      for (std::size_t k = 0; k < d.latent.size(); ++k)
        std::printf(" Q_%zu max rel. %.2e", k,
                    (f.latent[k].Q - d.latent[k].Q).cwiseAbs().maxCoeff() / d.latent[k].Q.cwiseAbs().maxCoeff());
      std::printf("\n");
    }
    for (const std::string& variant : variants) {
      selectGemmKernel(variant);
      for (const std::string& mode : modes) {
        CopaMap cm = initial;
        SvgpModel& model = cm.model();
        model.setMixedPrecision(mode == "mixed");
        for (auto& lat : model.latents())
          if (auto* st = dynamic_cast<SpatioTemporalKernel*>(lat.kernel.get())) st->use_value_tables = mode != "direct";
        std::mt19937_64 rng(seed);
        std::uniform_int_distribution<Eigen::Index> pick(0, train.X.rows() - 1);
        Eigen::MatrixXd Xb(batch, 3);
        Eigen::VectorXd yb(batch);
        const double scale = static_cast<double>(train.X.rows()) / batch;
        std::printf("\nGEMM %s, mode %s: m_f = %ld, m_g = %ld, batch %d, %d steps, %d OpenMP threads\n",
                    variant.c_str(), mode.c_str(), (long)model.latents()[0].Z.rows(),
                    (long)model.latents()[1].Z.rows(), batch, steps, Eigen::nbThreads());
        std::printf("| phase | CPU s/step | wall s/step |\n|---|---|---|\n");
        // Factorize K_uu once before timing (the first evaluate would otherwise include it).
        (void)model.evaluate(train.X.topRows(batch), ys.head(batch), scale, false);
        double ce = 0, we = 0, ch = 0, wh = 0, cn = 0, wn = 0, cr = 0, wr = 0;
        double elbo = 0;
        for (int s = 0; s < steps; ++s) {
          for (int i = 0; i < batch; ++i) {
            const Eigen::Index r = pick(rng);
            Xb.row(i) = train.X.row(r);
            yb[i] = ys[r];
          }
          Timer te;
          const ElboEvaluation ev = model.evaluate(Xb, yb, scale, false);
          ce += te.cpu();
          we += te.wall();
          Timer th;
          const ElboEvaluation evh = model.evaluate(Xb, yb, scale, true);
          ch += th.cpu();
          wh += th.wall();
          Timer tn;
          for (int k = 0; k < 2; ++k) model.naturalGradientStep(k, ev, scale, 0.1);
          cn += tn.cpu();
          wn += tn.wall();
          // What an Adam step adds to the next batch: K_uu, its factor and inverse are recomputed (a relative
          // change of 1e-12 in the parameters invalidates the cache without changing the model).
          model.setHyperParams(model.hyperParams() * (1.0 + 1e-12));
          Timer tr;
          const ElboEvaluation evr = model.evaluate(Xb, yb, scale, false);
          cr += tr.cpu() - ce / (s + 1);
          wr += tr.wall() - we / (s + 1);
          elbo = ev.elbo / static_cast<double>(train.X.rows());
          (void)evh;
          (void)evr;
        }
        {
          const auto& lat = model.latents()[0];
          Timer tk;
          const Eigen::MatrixXd Knu = lat.kernel->K(Xb, lat.Z);
          const double ck = tk.cpu(), wk = tk.wall();
          Timer tg;
          const Eigen::VectorXd gk = lat.kernel->gradK(Xb, lat.Z, Knu);
          std::printf("| of which kernel K(X_b, Z_f) / its gradient | %.3f / %.3f | %.3f / %.3f |\n", ck, tg.cpu(),
                      wk, tg.wall());
          (void)gk;
        }
        std::printf("| evaluate (ELBO, moments, Q) | %.3f | %.3f |\n", ce / steps, we / steps);
        std::printf("| evaluate + hyperparameter gradient | %.3f | %.3f |\n", ch / steps, wh / steps);
        std::printf("| natural-gradient steps (f and g) | %.3f | %.3f |\n", cn / steps, wn / steps);
        std::printf("| K_uu refactorization after an Adam step (approx.) | %.3f | %.3f |\n", cr / steps, wr / steps);
        std::printf("| step without / with Adam | %.3f / %.3f | %.3f / %.3f |\n", (ce + cn) / steps,
                    (ch + cn + cr) / steps, (we + wn) / steps, (wh + wn + wr) / steps);
        std::printf("| mean of a batch with Adam every 2nd | %.3f | %.3f |\n", (ce + ch + 2 * cn + cr) / (2 * steps),
                    (we + wh + 2 * wn + wr) / (2 * steps));
        std::printf("last ELBO/n %.9f\n", elbo);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  }
  return 0;
}
