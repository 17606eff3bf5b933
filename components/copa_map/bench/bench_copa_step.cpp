// Cost of one CoPA-Map training step on the ATC split (Stüde 2024, §4.2.5): CPU seconds and wall seconds per
// mini-batch at the authors' inducing points (m_f = 1,915 full, every 4th reduced), with and without the
// hyperparameter gradient, for the phases of a step (ELBO evaluation, natural-gradient steps). Used to measure
// the per-batch cost changes recorded in docs/benchmarks.md: every GEMM variant the CPU can run (portable
// "generic" = before, avx2/avx512 = run-time dispatch) is measured in the same run on the same batches.
//   bench_copa_step [--data DIR] [--reduced] [--batch B] [--steps N] [--seed N] [--gemm a,b,...]
#include <time.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "cairn/copa_map/copa_map.hpp"
#include "cairn/copa_map/cpu_dispatch.hpp"
#include "cairn/copa_map/io.hpp"

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
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) dir = argv[++i];
    else if (a == "--reduced") reduced = true;
    else if (a == "--batch" && i + 1 < argc) batch = std::atoi(argv[++i]);
    else if (a == "--steps" && i + 1 < argc) steps = std::atoi(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::strtoul(argv[++i], nullptr, 10);
    else if (a == "--gemm" && i + 1 < argc) {
      variants.clear();
      std::string list = argv[++i];
      for (std::size_t p = 0; p <= list.size();) {
        const std::size_t q = std::min(list.find(',', p), list.size());
        variants.push_back(list.substr(p, q - p));
        p = q + 1;
      }
    } else {
      std::fprintf(stderr, "usage: %s [--data DIR] [--reduced] [--batch B] [--steps N] [--seed N] [--gemm a,b]\n",
                   argv[0]);
      return 2;
    }
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
    for (const std::string& variant : variants) {
    selectGemmKernel(variant);
    CopaMap cm = initial;
    SvgpModel& model = cm.model();
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<Eigen::Index> pick(0, train.X.rows() - 1);
    Eigen::MatrixXd Xb(batch, 3);
    Eigen::VectorXd yb(batch);
    const double scale = static_cast<double>(train.X.rows()) / batch;
    std::printf("\nGEMM %s: m_f = %ld, m_g = %ld, batch %d, %d steps, %d OpenMP threads\n", variant.c_str(),
                (long)model.latents()[0].Z.rows(), (long)model.latents()[1].Z.rows(), batch, steps,
                Eigen::nbThreads());
    std::printf("| phase | CPU s/step | wall s/step |\n|---|---|---|\n");
    double ce = 0, we = 0, ch = 0, wh = 0, cn = 0, wn = 0;
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
      elbo = ev.elbo / static_cast<double>(train.X.rows());
      (void)evh;
    }
    {
      const auto& lat = model.latents()[0];
      Timer tk;
      const Eigen::MatrixXd Knu = lat.kernel->K(Xb, lat.Z);
      const double ck = tk.cpu(), wk = tk.wall();
      Timer tg;
      const Eigen::VectorXd gk = lat.kernel->gradK(Xb, lat.Z, Knu);
      std::printf("| of which kernel K(X_b, Z_f) / its gradient | %.3f / %.3f | %.3f / %.3f |\n", ck, tg.cpu(), wk,
                  tg.wall());
      (void)gk;
    }
    std::printf("| evaluate (ELBO, moments, Q) | %.3f | %.3f |\n", ce / steps, we / steps);
    std::printf("| evaluate + hyperparameter gradient | %.3f | %.3f |\n", ch / steps, wh / steps);
    std::printf("| natural-gradient steps (f and g) | %.3f | %.3f |\n", cn / steps, wn / steps);
    std::printf("| step without / with Adam | %.3f / %.3f | %.3f / %.3f |\n", (ce + cn) / steps, (ch + cn) / steps,
                (we + wn) / steps, (wh + wn) / steps);
    std::printf("last ELBO/n %.9f\n", elbo);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  }
  return 0;
}
