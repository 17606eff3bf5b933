// cairn-slam-bench: cairn's pose-graph optimizer vs Ceres 2.1 (SPARSE_NORMAL_CHOLESKY on SuiteSparse) on the
// public g2o benchmarks, same residuals (g2o error convention), same starting values, same tolerances and
// thread count. Prints per dataset the final chi2 and the median wall time of both, and the time ratio.
// With --outliers it runs the robustness experiment: M3500 + N random false loop closures.
//
//   cairn-slam-bench [--data DIR] [--runs N] [--threads T] [--max-iters N] [--only NAME] [--outliers N]
//
// This is the only translation unit of the package that includes Ceres.
#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/gnc.hpp"
#include "cairn/graph_slam/initialization.hpp"
#include "cairn/graph_slam/optimizer.hpp"

namespace gs = cairn::graph_slam;

namespace {

// ---- Ceres residuals: the same errors as cairn (factors.hpp), whitened by the upper Cholesky factor of Omega.

template <typename T>
T wrapAngle(const T& a) {
  const T two_pi(2.0 * M_PI);
  return a - two_pi * ceres::floor((a + T(M_PI)) / two_pi);
}

struct Between2Cost {
  Between2Cost(const gs::Pose2& z, const Eigen::Matrix3d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}
  template <typename T>
  bool operator()(const T* xi, const T* xj, T* residual) const {
    const T ci = ceres::cos(xi[2]), si = ceres::sin(xi[2]);
    const T dx = xj[0] - xi[0], dy = xj[1] - xi[1];
    const T tx = ci * dx + si * dy, ty = -si * dx + ci * dy;  // Ri^T (tj - ti)
    const T ux = tx - T(z_.t.x()), uy = ty - T(z_.t.y());
    const T cz(std::cos(z_.theta)), sz(std::sin(z_.theta));
    Eigen::Matrix<T, 3, 1> e;
    e << cz * ux + sz * uy, -sz * ux + cz * uy, wrapAngle(xj[2] - xi[2] - T(z_.theta));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> r(residual);
    r = sqrt_info_.cast<T>() * e;
    return true;
  }
  gs::Pose2 z_;
  Eigen::Matrix3d sqrt_info_;
};

struct Between3Cost {
  Between3Cost(const gs::Pose3& z, const gs::Matrix6d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}
  template <typename T>
  bool operator()(const T* ti_p, const T* qi_p, const T* tj_p, const T* qj_p, T* residual) const {
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> ti(ti_p), tj(tj_p);
    Eigen::Map<const Eigen::Quaternion<T>> qi(qi_p), qj(qj_p);
    const Eigen::Quaternion<T> qi_inv = qi.conjugate();
    const Eigen::Matrix<T, 3, 1> t_ij = qi_inv * (tj - ti);
    const Eigen::Quaternion<T> qz = z_.q.cast<T>();
    Eigen::Quaternion<T> qe = qz.conjugate() * (qi_inv * qj);
    qe.normalize();
    if (qe.w() < T(0)) qe.coeffs() = -qe.coeffs();
    Eigen::Matrix<T, 6, 1> e;
    e.template head<3>() = qz.conjugate() * (t_ij - z_.t.cast<T>());
    e.template tail<3>() = qe.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r = sqrt_info_.cast<T>() * e;
    return true;
  }
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

CeresRun solveWithCeres(gs::PoseGraph graph, const gs::OptimizerOptions& opt, const gs::RobustKernel& kernel) {
  const auto gauge = gs::automaticGauge(graph);
  const auto& vars = graph.variables();
  std::vector<std::array<double, 3>> p2(vars.size());
  std::vector<std::array<double, 3>> t3(vars.size());
  std::vector<std::array<double, 4>> q3(vars.size());
  for (std::size_t k = 0; k < vars.size(); ++k) {
    p2[k] = {vars[k].pose2.t.x(), vars[k].pose2.t.y(), vars[k].pose2.theta};
    t3[k] = {vars[k].pose3.t.x(), vars[k].pose3.t.y(), vars[k].pose3.t.z()};
    q3[k] = {vars[k].pose3.q.x(), vars[k].pose3.q.y(), vars[k].pose3.q.z(), vars[k].pose3.q.w()};
  }
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  ceres::EigenQuaternionManifold quat_manifold;
  ceres::LossFunction* loss = nullptr;
  if (kernel.type == gs::RobustKernel::Type::kHuber) loss = new ceres::HuberLoss(kernel.delta);
  if (kernel.type == gs::RobustKernel::Type::kCauchy) loss = new ceres::CauchyLoss(kernel.delta);
  for (const gs::Factor& f : graph.factors()) {
    const std::size_t i = f.var[0], j = f.var[1];
    if (f.kind == gs::FactorKind::kBetween2) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Between2Cost, 3, 3, 3>(
                                   new Between2Cost(f.z2, sqrtInfo<3>(f.information))),
                               loss, p2[i].data(), p2[j].data());
    } else if (f.kind == gs::FactorKind::kBetween3) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Between3Cost, 6, 3, 4, 3, 4>(
                                   new Between3Cost(f.z3, sqrtInfo<6>(f.information))),
                               loss, t3[i].data(), q3[i].data(), t3[j].data(), q3[j].data());
      problem.SetManifold(q3[i].data(), &quat_manifold);
      problem.SetManifold(q3[j].data(), &quat_manifold);
    } else {
      std::fprintf(stderr, "cairn-slam-bench: only relative-pose factors are benchmarked\n");
      std::exit(2);
    }
  }
  if (gauge) {
    const std::size_t g = *gauge;
    if (vars[g].kind == gs::VariableKind::kPose2) {
      problem.SetParameterBlockConstant(p2[g].data());
    } else {
      problem.SetParameterBlockConstant(t3[g].data());
      problem.SetParameterBlockConstant(q3[g].data());
    }
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
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
  if (std::getenv("CAIRN_BENCH_CERES_REPORT") != nullptr) std::fprintf(stderr, "%s\n", summary.FullReport().c_str());
  CeresRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.iterations = static_cast<int>(summary.iterations.size()) - 1;
  run.converged = summary.termination_type == ceres::CONVERGENCE;
  // chi2 evaluated by cairn on Ceres's values (identical error definition).
  std::vector<gs::Variable> out = vars;
  for (std::size_t k = 0; k < vars.size(); ++k) {
    out[k].pose2 = gs::Pose2{Eigen::Vector2d(p2[k][0], p2[k][1]), gs::normalizeAngle(p2[k][2])};
    out[k].pose3.t = Eigen::Vector3d(t3[k][0], t3[k][1], t3[k][2]);
    out[k].pose3.q = Eigen::Quaterniond(q3[k][3], q3[k][0], q3[k][1], q3[k][2]).normalized();
  }
  graph.setValues(out);
  run.chi2 = graph.chi2();
  return run;
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

int outlierExperiment(const std::string& data, int count, const gs::OptimizerOptions& opt) {
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
    gs::PoseGraph g = corrupted;
    g.setRobustKernelAll(gs::RobustKernel::parse(k));
    const auto sum = gs::Optimizer(opt).optimize(g);
    const double ate = ate2d(g, truth);
    std::printf("%-14s %12.4f %12.4f %14.4f %10.3f %8d\n", k, ate, ate / ate_clean, ate2d(g, clean_xy), sum.time_s,
                sum.iterations);
  }
  {
    gs::PoseGraph g = corrupted;
    gs::Optimizer optimizer(opt);
    const auto sum = gs::optimizeGnc(g, optimizer);
    const double ate = ate2d(g, truth);
    std::printf("%-14s %12.4f %12.4f %14.4f %10.3f %8d  (%zu rejected, %d outer)\n", "gnc-gm", ate, ate / ate_clean,
                ate2d(g, clean_xy), sum.time_s, sum.inner_iterations, sum.rejected, sum.outer_iterations);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(CAIRN_SOURCE_ROOT) + "/../shared/data/pose_graph_g2o";
  int runs = 3;
  int outliers = 0;
  std::string only;
  gs::OptimizerOptions opt;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto next = [&]() -> std::string {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "cairn-slam-bench: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (a == "--data") data = next();
    else if (a == "--runs") runs = std::max(1, std::atoi(next().c_str()));
    else if (a == "--threads") opt.num_threads = std::max(1, std::atoi(next().c_str()));
    else if (a == "--max-iters") opt.max_iterations = std::atoi(next().c_str());
    else if (a == "--only") only = next();
    else if (a == "--outliers") outliers = std::atoi(next().c_str());
    else if (a == "--ordering") {
      const std::string v = next();
      opt.ordering = v == "amd" ? gs::Ordering::kAmd : v == "nd" ? gs::Ordering::kNestedDissection : gs::Ordering::kAuto;
    } else if (a == "--factorization") {
      const std::string v = next();
      opt.factorization = v == "simplicial"   ? gs::Factorization::kSimplicial
                          : v == "supernodal" ? gs::Factorization::kSupernodal
                                              : gs::Factorization::kAuto;
    }
    else {
      std::fprintf(stderr, "usage: cairn-slam-bench [--data DIR] [--runs N] [--threads T] [--max-iters N] [--only NAME] [--outliers N]\n"
                   "                        [--ordering auto|amd|nd] [--factorization auto|simplicial|supernodal]\n");
      return 2;
    }
  }
  if (outliers > 0) return outlierExperiment(data, outliers, opt);

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
  std::printf("# cairn LM vs Ceres 2.1 LM (SPARSE_NORMAL_CHOLESKY, SUITE_SPARSE), stored initial values,\n"
              "# max %d iterations, function tol %g, gradient tol %g, parameter tol %g, %d threads, median of %d runs\n",
              opt.max_iterations, opt.function_tolerance, opt.gradient_tolerance, opt.parameter_tolerance,
              opt.num_threads, runs);
  std::printf("%-16s %8s %8s %16s %16s %10s %5s %10s %5s %7s %s\n", "dataset", "vertices", "edges", "cairn_chi2",
              "ceres_chi2", "cairn_s", "it", "ceres_s", "it", "ratio", "notes");
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
    std::vector<double> tc, tr;
    gs::OptimizerSummary cs;
    CeresRun cr;
    for (int r = 0; r < runs; ++r) {
      gs::PoseGraph g = graph;
      gs::Optimizer optimizer(opt);
      cs = optimizer.optimize(g);
      tc.push_back(cs.time_s);
      cr = solveWithCeres(graph, opt, gs::RobustKernel{});
      tr.push_back(cr.seconds);
    }
    const double mc = median(tc), mr = median(tr);
    std::string notes;
    if (rep.clamped_information > 0) notes += std::to_string(rep.clamped_information) + " info clamped; ";
    if (!cs.converged) notes += "cairn not converged; ";
    if (!cr.converged) notes += "ceres not converged; ";
    std::printf("%-16s %8zu %8zu %16.9g %16.9g %10.4f %5d %10.4f %5d %7.3f %s\n", d.name.c_str(),
                graph.variables().size(), graph.factors().size(), cs.final_chi2, cr.chi2, mc, cs.iterations, mr,
                cr.iterations, mc / mr, notes.c_str());
    std::fflush(stdout);
  }
  return 0;
}
