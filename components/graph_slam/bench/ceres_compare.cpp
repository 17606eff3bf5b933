// cairn-slam-bench: cairn's pose-graph optimizer vs Ceres 2.1 (SPARSE_NORMAL_CHOLESKY on SuiteSparse) on the
// public g2o benchmarks: same residuals and Jacobians (g2o error convention), same manifolds, same starting
// values, tolerances and thread count. Prints per dataset the final chi2 and the median wall time of both, the
// time ratio, and cairn's result from chordal initialization. With --outliers N: the robustness experiment
// (M3500 + N random false loop closures; --only selects rows by kernel / GNC variant name).
//
//   cairn-slam-bench [--data DIR] [--runs N] [--threads T] [--max-iters N] [--only NAME] [--outliers N]
//                    [--solver lm|gn|dogleg] [--ceres-solver lm|dogleg] [--ordering auto|amd|nd]
//                    [--factorization auto|simplicial|supernodal] [--no-chordal]
//                    [--profile] [--trace] [--incremental] [--reuse-min-gain G] [--certify-iters N]
//
// --incremental replays M3500 (or --only intel / city) as a SLAM front end would (see incrementalExperiment).
// Per dataset the SE-Sync objective at cairn's solutions and SE-Sync's verification certificate of them
// ("certified global optimum: yes/no", certificate.hpp) from the stored guess and from chordal initialization.
//
// This is the only translation unit of the package that includes Ceres.
#include <ceres/ceres.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "cairn/graph_slam/certificate.hpp"
#include "cairn/graph_slam/factors.hpp"
#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/gnc.hpp"
#include "cairn/graph_slam/initialization.hpp"
#include "cairn/graph_slam/optimizer.hpp"

namespace gs = cairn::graph_slam;

namespace {

// ---- Ceres side. Analytic cost functions built on cairn's error functions, whitened by the upper Cholesky
// factor of Omega, so Ceres solves exactly the same problem and only the solver machinery differs. (Analytic
// cost functions also keep this translation unit cheap to compile; an autodiff variant took minutes on 2 cores.)

// SE3 as one 7-vector [t, q(x y z w)] with cairn's retract. Cost functions return the 6 tangent Jacobian
// columns in the first 6 ambient columns (7th zero) and PlusJacobian = [I6; 0], so the product is exact.
class Se3Manifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    const gs::Pose3 r = gs::retract(toPose(x), gs::Vector6d(Eigen::Map<const gs::Vector6d>(delta)));
    fromPose(r, x_plus_delta);
    return true;
  }
  bool PlusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> j(jacobian);
    j.setZero();
    j.topRows<6>().setIdentity();
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const gs::Pose3 px = toPose(x), py = toPose(y);
    Eigen::Map<gs::Vector6d> d(y_minus_x);
    d.head<3>() = px.q.conjugate() * (py.t - px.t);
    d.tail<3>() = gs::logSO3(px.q.conjugate() * py.q);
    return true;
  }
  bool MinusJacobian(const double*, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> j(jacobian);
    j.setZero();
    j.leftCols<6>().setIdentity();
    return true;
  }
  static gs::Pose3 toPose(const double* x) {
    gs::Pose3 p;
    p.t = Eigen::Vector3d(x[0], x[1], x[2]);
    p.q = Eigen::Quaterniond(x[6], x[3], x[4], x[5]);
    return p;
  }
  static void fromPose(const gs::Pose3& p, double* x) {
    x[0] = p.t.x();
    x[1] = p.t.y();
    x[2] = p.t.z();
    x[3] = p.q.x();
    x[4] = p.q.y();
    x[5] = p.q.z();
    x[6] = p.q.w();
  }
};

class Between2Cost final : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  Between2Cost(const gs::Pose2& z, const Eigen::Matrix3d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const gs::Pose2 xi{Eigen::Vector2d(p[0][0], p[0][1]), p[0][2]};
    const gs::Pose2 xj{Eigen::Vector2d(p[1][0], p[1][1]), p[1][2]};
    Eigen::Matrix3d ji, jj;
    const bool jac = jacobians != nullptr;
    const Eigen::Vector3d e = gs::errorBetween2(xi, xj, z_, jac ? &ji : nullptr, jac ? &jj : nullptr);
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = sqrt_info_ * e;
    using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    if (jac && jacobians[0] != nullptr) {
      Eigen::Map<RowMajor3> j0(jacobians[0]);
      j0 = sqrt_info_ * ji;
    }
    if (jac && jacobians[1] != nullptr) {
      Eigen::Map<RowMajor3> j1(jacobians[1]);
      j1 = sqrt_info_ * jj;
    }
    return true;
  }

 private:
  gs::Pose2 z_;
  Eigen::Matrix3d sqrt_info_;
};

class Between3Cost final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  Between3Cost(const gs::Pose3& z, const gs::Matrix6d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    gs::Matrix6d ji, jj;
    const bool jac = jacobians != nullptr;
    const gs::Vector6d e = gs::errorBetween3(Se3Manifold::toPose(p[0]), Se3Manifold::toPose(p[1]), z_,
                                             jac ? &ji : nullptr, jac ? &jj : nullptr);
    Eigen::Map<gs::Vector6d> r(residuals);
    r = sqrt_info_ * e;
    for (int b = 0; b < 2 && jac; ++b) {
      if (jacobians[b] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> j(jacobians[b]);
      j.setZero();
      j.leftCols<6>() = sqrt_info_ * (b == 0 ? ji : jj);
    }
    return true;
  }

 private:
  gs::Pose3 z_;
  gs::Matrix6d sqrt_info_;
};

template <int D>
Eigen::Matrix<double, D, D> sqrtInfo(const gs::Matrix6d& info) {
  const Eigen::Matrix<double, D, D> om = info.topLeftCorner<D, D>();
  return om.llt().matrixU();  // U^T U = Omega, so |U e|^2 = e^T Omega e
}

struct CeresRun {
  double chi2 = 0.0;
  double seconds = 0.0;
  int iterations = 0;
  bool converged = false;
};

CeresRun solveWithCeres(gs::PoseGraph graph, const gs::OptimizerOptions& opt, bool dogleg) {
  const auto gauge = gs::automaticGauge(graph);  // the same gauge as cairn: the first pose held constant
  const auto& vars = graph.variables();
  std::vector<std::array<double, 3>> p2(vars.size());
  std::vector<std::array<double, 7>> p3(vars.size());
  for (std::size_t k = 0; k < vars.size(); ++k) {
    p2[k] = {vars[k].pose2.t.x(), vars[k].pose2.t.y(), vars[k].pose2.theta};
    Se3Manifold::fromPose(vars[k].pose3, p3[k].data());
  }
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  Se3Manifold se3_manifold;
  for (const gs::Factor& f : graph.factors()) {
    const std::size_t i = f.var[0], j = f.var[1];
    if (f.kind == gs::FactorKind::kBetween2) {
      problem.AddResidualBlock(new Between2Cost(f.z2, sqrtInfo<3>(f.information)), nullptr, p2[i].data(),
                               p2[j].data());
    } else if (f.kind == gs::FactorKind::kBetween3) {
      problem.AddResidualBlock(new Between3Cost(f.z3, sqrtInfo<6>(f.information)), nullptr, p3[i].data(),
                               p3[j].data());
      problem.SetManifold(p3[i].data(), &se3_manifold);
      problem.SetManifold(p3[j].data(), &se3_manifold);
    } else {
      std::fprintf(stderr, "cairn-slam-bench: only relative-pose factors are benchmarked\n");
      std::exit(2);
    }
  }
  if (gauge) {
    const std::size_t g = *gauge;
    problem.SetParameterBlockConstant(vars[g].kind == gs::VariableKind::kPose2 ? p2[g].data() : p3[g].data());
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = dogleg ? ceres::DOGLEG : ceres::LEVENBERG_MARQUARDT;
  so.dogleg_type = ceres::TRADITIONAL_DOGLEG;  // Powell's dogleg, as cairn's
  so.initial_trust_region_radius = dogleg ? opt.initial_radius : 1.0 / opt.initial_lambda;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  so.max_num_iterations = opt.max_iterations;
  so.function_tolerance = opt.function_tolerance;
  so.gradient_tolerance = opt.gradient_tolerance;
  so.parameter_tolerance = opt.parameter_tolerance;
  so.num_threads = opt.num_threads;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solve(so, &problem, &summary);
  CeresRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (std::getenv("CAIRN_BENCH_CERES_REPORT") != nullptr) std::fprintf(stderr, "%s\n", summary.FullReport().c_str());
  run.iterations = static_cast<int>(summary.iterations.size()) - 1;
  run.converged = summary.termination_type == ceres::CONVERGENCE;
  // chi2 evaluated by cairn on Ceres's values (identical error definition).
  std::vector<gs::Variable> out = vars;
  for (std::size_t k = 0; k < vars.size(); ++k) {
    out[k].pose2 = gs::Pose2{Eigen::Vector2d(p2[k][0], p2[k][1]), gs::normalizeAngle(p2[k][2])};
    out[k].pose3 = Se3Manifold::toPose(p3[k].data());
    out[k].pose3.q.normalize();
  }
  graph.setValues(out);
  run.chi2 = graph.chi2();
  return run;
}

// SE-Sync's verification certificate (core: certificate.hpp) at cairn's solution: refine to a critical point of
// SE-Sync's objective f, then decide S = M - Lambda(Y) >= 0. One line fragment "yes/no (lambda_min ...)".
// The refinement is capped at --certify-iters (150) LM solves here (sphere_bignoise converges only linearly: 1000
// solves took 400 s); where it stops short, "yes" still bounds f* from below by the dual bound less its tolerance
// slack (certificate.hpp), while "no" is inconclusive (not a critical point).
std::string certificateText(const gs::PoseGraph& g, int max_iterations) {
  gs::CertificateOptions co;
  co.max_iterations = max_iterations;
  const gs::CertificateResult c = gs::certifyGlobalOptimum(g, co);
  char buf[400];
  if (c.certified) {
    std::snprintf(buf, sizeof(buf),
                  "yes (lambda_min in [%.2g, %.2g], eta %.2g, next %.3g; f %.10g -> %.10g >= f* >= %.10g - %.2g, "
                  "%d LM solves%s, %.2f s)",
                  c.lambda_min_lower, c.lambda_min_upper, c.eta, c.lambda_deflated, c.objective_input, c.objective, c.dual_bound,
                  c.dual_bound_slack, c.refine_iterations, c.refine_converged ? "" : " (not converged)", c.time_s);
  } else {
    std::snprintf(buf, sizeof(buf), "no (lambda_min %.4g, eta %.2g; f %.10g -> %.10g, %d LM solves%s, %.2f s)",
                  c.lambda_min, c.eta, c.objective_input, c.objective, c.refine_iterations,
                  c.refine_converged ? "" : " NOT CONVERGED: not a critical point", c.time_s);
  }
  return buf;
}

// Process CPU time (all threads), less sensitive than wall time to other jobs on a shared machine.
double cpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + 1e-6 * u.ru_utime.tv_usec + u.ru_stime.tv_sec + 1e-6 * u.ru_stime.tv_usec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Dataset {
  std::string name;
  std::string path;
  bool clamp = false;
};

// Absolute trajectory error (RMSE of positions) after the best rigid 2D alignment (Umeyama without scale).
double ate2d(const gs::PoseGraph& g, const std::vector<Eigen::Vector2d>& ref) {
  const std::size_t n = ref.size();
  Eigen::Vector2d mg = Eigen::Vector2d::Zero(), mr = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mg += g.pose2(static_cast<gs::VariableId>(i)).t;
    mr += ref[i];
  }
  mg /= n;
  mr /= n;
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < n; ++i) c += (ref[i] - mr) * (g.pose2(static_cast<gs::VariableId>(i)).t - mg).transpose();
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(c, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix2d s = Eigen::Matrix2d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) s(1, 1) = -1;
  const Eigen::Matrix2d r = svd.matrixU() * s * svd.matrixV().transpose();
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p = r * (g.pose2(static_cast<gs::VariableId>(i)).t - mg) + mr;
    sum += (p - ref[i]).squaredNorm();
  }
  return std::sqrt(sum / n);
}

int outlierExperiment(const std::string& data, int count, const gs::OptimizerOptions& opt, const std::string& only) {
  const std::string file = data + "/vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o";
  const std::string gt_file = data + "/vertigo/manhattan/groundTruth/manhattanOlson3500_nodes_groundTruth.dat";
  std::vector<Eigen::Vector2d> truth;
  {
    std::ifstream in(gt_file);
    double x, y, th;
    while (in >> x >> y >> th) truth.emplace_back(x, y);
  }
  const gs::PoseGraph base = gs::readG2o(file);
  if (truth.size() != base.variables().size()) {
    std::fprintf(stderr, "ground truth size mismatch\n");
    return 2;
  }
  gs::PoseGraph clean = base;
  gs::Optimizer(opt).optimize(clean);
  const double ate_clean = ate2d(clean, truth);
  std::vector<Eigen::Vector2d> clean_xy;
  for (const auto& v : clean.variables()) clean_xy.push_back(v.pose2.t);

  // False loop closures: uniformly random vertex pairs with a plausible-looking random relative pose
  // (|t| <= 2 m, any heading) and the data set's loop-closure information (seeded: reproducible).
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(base.variables().size()) - 1);
  std::uniform_real_distribution<double> ut(-2.0, 2.0), ua(-M_PI, M_PI);
  const Eigen::Matrix3d info = base.factors().back().information.topLeftCorner<3, 3>();
  gs::PoseGraph corrupted = base;
  for (int k = 0; k < count;) {
    const int i = pick(rng), j = pick(rng);
    if (std::abs(i - j) < 2) continue;
    corrupted.addBetween2(i, j, gs::Pose2{Eigen::Vector2d(ut(rng), ut(rng)), ua(rng)}, info);
    ++k;
  }
  std::printf("## outlier robustness: M3500 (g2o, 5598 edges) + %d random false loop closures (seed 42)\n", count);
  std::printf("outlier-free solution: ATE %.4f m vs ground truth\n", ate_clean);
  std::printf("%-14s %12s %12s %14s %10s %8s\n", "kernel", "ATE_gt[m]", "ATE/clean", "ATE_vs_clean[m]", "time[s]", "iters");
  for (const char* k : {"none", "huber:1", "cauchy:1", "gm:1", "dcs:1", "dcs:10"}) {
    if (!only.empty() && std::string(k).find(only) == std::string::npos) continue;
    gs::PoseGraph g = corrupted;
    g.setRobustKernelAll(gs::RobustKernel::parse(k));
    const auto sum = gs::Optimizer(opt).optimize(g);
    const double ate = ate2d(g, truth);
    std::printf("%-14s %12.4f %12.4f %14.4f %10.3f %8d\n", k, ate, ate / ate_clean, ate2d(g, clean_xy), sum.time_s,
                sum.iterations);
    std::fflush(stdout);
  }
  // GNC variants: surrogate x start (least-squares solution as in Yang et al., or the stored odometry guess).
  // Rejected false closures are counted against the injected ones (factor index >= base count).
  const std::size_t base_factors = base.factors().size();
  for (const bool tls : {false, true}) {
    for (const bool from_ls : {true, false}) {
      const std::string name = std::string(tls ? "gnc-tls" : "gnc-gm") + (from_ls ? "" : "(odom)");
      if (!only.empty() && name.find(only) == std::string::npos) continue;
      gs::PoseGraph g = corrupted;
      gs::Optimizer optimizer(opt);
      gs::GncOptions go;
      go.surrogate = tls ? gs::GncSurrogate::kTruncatedLeastSquares : gs::GncSurrogate::kGemanMcClure;
      go.start_from_least_squares = from_ls;
      const auto sum = gs::optimizeGnc(g, optimizer, go);
      std::size_t false_rejected = 0;
      for (std::size_t k = base_factors; k < sum.weights.size(); ++k) false_rejected += sum.weights[k] < 0.5;
      const double ate = ate2d(g, truth);
      std::printf("%-14s %12.4f %12.4f %14.4f %10.3f %8d  (%zu rejected: %zu of %d false, %zu true; %d outer)\n",
                  name.c_str(), ate, ate / ate_clean, ate2d(g, clean_xy), sum.time_s, sum.inner_iterations,
                  sum.rejected, false_rejected, count, sum.rejected - false_rejected, sum.outer_iterations);
      // Diagnostic: GNC's inlier set (weight >= 0.5) re-solved by least squares from the stored guess, which
      // separates a wrong inlier set from a wrong basin of the continuation.
      gs::PoseGraph refit = corrupted;
      for (std::size_t k = 0; k < sum.weights.size(); ++k) refit.setFactorWeight(k, sum.weights[k] >= 0.5 ? 1.0 : 0.0);
      gs::Optimizer(opt).optimize(refit);
      std::printf("%-14s %12.4f %12.4f %14.4f   (GNC's inlier set re-solved from the stored guess)\n", "  refit",
                  ate2d(refit, truth), ate2d(refit, truth) / ate_clean, ate2d(refit, clean_xy));
      std::fflush(stdout);
    }
  }
  return 0;
}

// Incremental use as a SLAM front end drives it: replay a 2D data set in vertex order, appending each pose
// (initialized by composing the previous estimate with the odometry) with its edges to earlier poses, and
// re-optimize (warm-started, one Optimizer) whenever a loop closure arrived. Compares incremental ordering
// (keep the elimination order, append new poses) against a fresh ordering at every structure change.
int incrementalExperiment(const std::string& data, const std::string& only, const gs::OptimizerOptions& base_opt,
                          int runs) {
  const std::string rel = only.empty() || only == "M3500" ? "carlone/input_M3500_g2o.g2o"
                          : only == "intel"                ? "vertigo/intel/originalDataset/intel.g2o"
                                                           : "vertigo/city10000/originalDataset/city10000.g2o";
  const gs::PoseGraph full = gs::readG2o(data + "/" + rel);
  const auto& vars = full.variables();
  // Edges grouped by the later endpoint (the vertex whose arrival makes them available).
  std::vector<std::vector<std::size_t>> edges_at(vars.size());
  for (std::size_t k = 0; k < full.factors().size(); ++k) {
    const gs::Factor& f = full.factors()[k];
    if (f.kind != gs::FactorKind::kBetween2) continue;
    edges_at[std::max(f.var[0], f.var[1])].push_back(k);
  }
  std::printf("## incremental: %s replayed in vertex order, optimize() after every loop closure (median of %d)\n",
              rel.c_str(), runs);
  std::printf("%-22s %8s %12s %12s %12s %12s %10s %14s\n", "ordering", "solves", "total[s]", "structure[s]",
              "cpu[s]", "per_solve[ms]", "reordered", "final_chi2");
  double chi2_batch = 0.0;
  {
    gs::PoseGraph g = full;
    chi2_batch = gs::Optimizer(base_opt).optimize(g).final_chi2;
  }
  for (const bool incremental : {false, true}) {
    std::vector<double> tot, st, cpu;
    int solves = 0, fresh = 0;
    double chi2 = 0.0;
    for (int r = 0; r < runs; ++r) {
      gs::OptimizerOptions opt = base_opt;
      opt.incremental_ordering = incremental;
      opt.warm_start_damping = true;
      gs::Optimizer optimizer(opt);
      gs::PoseGraph g;
      double t = 0.0, ts = 0.0;
      solves = fresh = 0;
      const double c0 = cpuSeconds();
      for (std::size_t v = 0; v < vars.size(); ++v) {
        gs::Pose2 init = vars[v].pose2;
        bool loop = false;
        for (std::size_t k : edges_at[v]) {
          const gs::Factor& f = full.factors()[k];
          const std::size_t other = f.var[0] == v ? f.var[1] : f.var[0];
          if (v > 0 && other + 1 == v && f.var[0] == other) init = gs::compose(g.pose2(vars[other].id), f.z2);
          if (other + 1 != v) loop = true;
        }
        g.addPose2(vars[v].id, init);
        for (std::size_t k : edges_at[v]) {
          const gs::Factor& f = full.factors()[k];
          g.addBetween2(vars[f.var[0]].id, vars[f.var[1]].id, f.z2, f.information.topLeftCorner<3, 3>());
        }
        if (loop || v + 1 == vars.size()) {
          const gs::OptimizerSummary s = optimizer.optimize(g);
          t += s.time_s;
          ts += s.time_structure_s;
          ++solves;
          fresh += s.structure_rebuilt && !s.ordering_reused;
        }
      }
      cpu.push_back(cpuSeconds() - c0);
      tot.push_back(t);
      st.push_back(ts);
      chi2 = g.chi2();
    }
    std::printf("%-22s %8d %12.4f %12.4f %12.4f %12.3f %10d %14.9g\n",
                incremental ? "incremental (append)" : "fresh AMD every time", solves, median(tot), median(st),
                median(cpu), 1e3 * median(tot) / solves, fresh, chi2);
    std::fflush(stdout);
  }
  std::printf("batch optimize of the full graph: final chi2 %.9g\n", chi2_batch);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/pose_graph_g2o";
  int runs = 3;
  int outliers = 0;
  std::string only;
  gs::OptimizerOptions opt;
  bool ceres_dogleg = false;
  bool chordal = true;
  bool profile = false;
  bool incremental = false;
  int certify_iters = 150;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto next = [&]() -> std::string {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "cairn-slam-bench: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (a == "--data") {
      data = next();
    } else if (a == "--runs") {
      runs = std::max(1, std::atoi(next().c_str()));
    } else if (a == "--threads") {
      opt.num_threads = std::max(1, std::atoi(next().c_str()));
    } else if (a == "--max-iters") {
      opt.max_iterations = std::atoi(next().c_str());
    } else if (a == "--only") {
      only = next();
    } else if (a == "--outliers") {
      outliers = std::atoi(next().c_str());
    } else if (a == "--solver") {
      opt.algorithm = gs::parseAlgorithm(next());
    } else if (a == "--ceres-solver") {
      ceres_dogleg = next() == "dogleg";
    } else if (a == "--trace") {
      opt.trace = true;
    } else if (a == "--reuse-min-gain") {
      opt.factor_reuse_min_gain = std::atof(next().c_str());
    } else if (a == "--certify-iters") {
      certify_iters = std::max(0, std::atoi(next().c_str()));
    } else if (a == "--incremental") {
      incremental = true;
    } else if (a == "--profile") {
      profile = true;
    } else if (a == "--no-chordal") {
      chordal = false;
    } else if (a == "--ordering") {
      const std::string v = next();
      opt.ordering = v == "amd" ? gs::Ordering::kAmd : v == "nd" ? gs::Ordering::kNestedDissection : gs::Ordering::kAuto;
    } else if (a == "--factorization") {
      const std::string v = next();
      opt.factorization = v == "simplicial"   ? gs::Factorization::kSimplicial
                          : v == "supernodal" ? gs::Factorization::kSupernodal
                                              : gs::Factorization::kAuto;
    } else {
      std::fprintf(stderr,
                   "usage: cairn-slam-bench [--data DIR] [--runs N] [--threads T] [--max-iters N] [--only NAME]\n"
                   "         [--outliers N] [--solver lm|gn|dogleg] [--ceres-solver lm|dogleg]\n"
                   "         [--ordering auto|amd|nd] [--factorization auto|simplicial|supernodal] [--no-chordal]\n"
                   "         [--profile] [--trace] [--incremental] [--reuse-min-gain G] [--certify-iters N]\n");
      return 2;
    }
  }
  if (outliers > 0) return outlierExperiment(data, outliers, opt, only);
  if (incremental) return incrementalExperiment(data, only, opt, runs);

  const std::vector<Dataset> sets = {
      {"INTEL(carlone)", "carlone/input_INTEL_g2o.g2o"},
      {"intel(g2o)", "vertigo/intel/originalDataset/intel.g2o"},
      {"M3500(5453)", "carlone/input_M3500_g2o.g2o"},
      {"M3500(5598)", "vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o"},
      {"MIT", "se-sync/MIT.g2o"},
      {"city10000", "vertigo/city10000/originalDataset/city10000.g2o"},
      {"sphere2500", "vertigo/sphere2500/originalDataset/sphere2500.g2o"},
      {"sphere_bignoise", "se-sync/sphere_bignoise_vertex3.g2o"},
      {"parking-garage", "carlone/parking-garage.g2o"},
      {"torus3D", "se-sync/torus3D.g2o"},
      {"cubicle(clamp)", "se-sync/cubicle.g2o", true},
  };
  const char* cairn_alg = opt.algorithm == gs::Algorithm::kDogleg        ? "dogleg"
                          : opt.algorithm == gs::Algorithm::kGaussNewton ? "GN"
                                                                         : "LM";
  std::printf("# cairn %s vs Ceres 2.1 %s (SPARSE_NORMAL_CHOLESKY, SUITE_SPARSE; same analytic residuals), stored\n"
              "# initial values, max %d iterations, function tol %g, gradient tol %g, parameter tol %g, %d threads,\n"
              "# median of %d runs (cairn and Ceres interleaved)\n",
              cairn_alg, ceres_dogleg ? "dogleg" : "LM", opt.max_iterations, opt.function_tolerance,
              opt.gradient_tolerance, opt.parameter_tolerance, opt.num_threads, runs);
  std::printf("%-16s %6s %6s %15s %15s %9s %9s %4s %9s %4s %7s %9s %9s %7s %15s %9s %s\n", "dataset", "V", "E",
              "cairn_chi2", "ceres_chi2", "rel_diff", "cairn_s", "it", "ceres_s", "it", "ratio", "cairn_cpu",
              "ceres_cpu", "cpu_rat", "chordal_chi2", "chordal_s", "notes");
  for (const Dataset& d : sets) {
    if (!only.empty() && d.name.find(only) == std::string::npos) continue;
    gs::G2oReadOptions ro;
    if (d.clamp) ro.information_fix = gs::G2oReadOptions::InformationFix::kClamp;
    gs::G2oReadReport rep;
    gs::PoseGraph graph;
    try {
      graph = gs::readG2o(data + "/" + d.path, ro, &rep);
    } catch (const gs::G2oError& e) {
      std::fprintf(stderr, "cairn: %s\n", e.what());
      return 2;
    }
    std::vector<double> tc, tr, tch, cc, crr;
    gs::OptimizerSummary cs, chs;
    double sesync_guess = 0.0, sesync_chordal = 0.0;
    std::string cert_guess, cert_chordal;
    CeresRun cr;
    for (int r = 0; r < runs; ++r) {
      gs::PoseGraph g = graph;
      gs::Optimizer optimizer(opt);
      double c0 = cpuSeconds();
      cs = optimizer.optimize(g);
      cc.push_back(cpuSeconds() - c0);
      sesync_guess = gs::seSyncObjective(g);
      if (r == 0) cert_guess = certificateText(g, certify_iters);
      tc.push_back(cs.time_s);
      c0 = cpuSeconds();
      cr = solveWithCeres(graph, opt, ceres_dogleg);
      crr.push_back(cpuSeconds() - c0);  // includes building the Ceres problem (small)
      tr.push_back(cr.seconds);
      if (chordal) {
        gs::PoseGraph h = graph;
        const auto t0 = std::chrono::steady_clock::now();
        gs::initializeChordal(h);
        chs = gs::Optimizer(opt).optimize(h);
        tch.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        sesync_chordal = gs::seSyncObjective(h);
        if (r == 0) cert_chordal = certificateText(h, certify_iters);
      }
    }
    const double mc = median(tc), mr = median(tr);
    std::string notes;
    if (rep.clamped_information > 0) notes += std::to_string(rep.clamped_information) + " info clamped; ";
    if (!cs.converged) notes += "cairn not converged; ";
    if (!cr.converged) notes += "ceres not converged; ";
    if (chordal && !chs.converged) notes += "chordal run not converged; ";
    const double mcc = median(cc), mcr = median(crr);
    std::printf("%-16s %6zu %6zu %15.9g %15.9g %9.1e %9.4f %4d %9.4f %4d %7.3f %9.4f %9.4f %7.3f %15.9g %9.4f %s\n",
                d.name.c_str(), graph.variables().size(), graph.factors().size(), cs.final_chi2, cr.chi2,
                (cs.final_chi2 - cr.chi2) / cr.chi2, mc, cs.iterations, mr, cr.iterations, mc / mr, mcc, mcr,
                mcc / mcr, chordal ? chs.final_chi2 : 0.0, chordal ? median(tch) : 0.0, notes.c_str());
    std::printf("  SE-Sync objective f (Rosen et al. 2019 weights) at cairn's solution: from stored guess %.10g",
                sesync_guess);
    if (chordal) std::printf(", from chordal init %.10g", sesync_chordal);
    std::printf("\n");
    std::printf("  certified global optimum (SE-Sync certificate): from stored guess %s\n", cert_guess.c_str());
    if (chordal) std::printf("  certified global optimum (SE-Sync certificate): from chordal init %s\n", cert_chordal.c_str());
    if (profile) {
      std::printf("  cairn phases (last run) [s]: structure %.4f linearize %.4f factorize %.4f solve %.4f evaluate %.4f"
                  " other %.4f; %d factorizations%s, factor nnz %.0f, %.3g flop each\n",
                  cs.time_structure_s, cs.time_linearize_s, cs.time_factorize_s, cs.time_solve_s, cs.time_evaluate_s,
                  cs.time_s - cs.time_structure_s - cs.time_linearize_s - cs.time_factorize_s - cs.time_solve_s -
                      cs.time_evaluate_s,
                  cs.numeric_factorizations, cs.factorization_replayed ? " (replayed LDL^T)" : "", cs.factor_nonzeros,
                  cs.factor_flops);
    }
    std::fflush(stdout);
  }
  return 0;
}
