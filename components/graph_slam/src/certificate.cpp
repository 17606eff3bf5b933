// SE-Sync's verification certificate (Rosen et al., IJRR 2019): refine to a critical point of f, form the
// certificate matrix S = M - Lambda(Y) in the translation-explicit form and decide S ⪰ 0 with CHOLMOD.
// The math is in certificate.hpp; the README section "Global optimality" documents the choices.
#include "cairn/graph_slam/certificate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SparseCore>

#include "sparse_cholesky.hpp"

namespace cairn::graph_slam {

SeSyncWeights seSyncWeights(const Factor& f) {
  SeSyncWeights w;
  if (f.kind == FactorKind::kBetween2) {
    w.tau = 2.0 / f.information.topLeftCorner<2, 2>().inverse().trace();
    w.kappa = f.information(2, 2);
  } else if (f.kind == FactorKind::kBetween3) {
    w.tau = 3.0 / f.information.topLeftCorner<3, 3>().inverse().trace();
    w.kappa = 3.0 / (2.0 * f.information.bottomRightCorner<3, 3>().inverse().trace());
  } else {
    throw std::invalid_argument("SE-Sync weights: only relative-pose factors (EDGE_SE2, EDGE_SE3:QUAT)");
  }
  return w;
}

namespace {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Triplets = std::vector<Eigen::Triplet<double>>;

// Checks the graph and returns d (2 or 3) and the pose index of every variable.
int checkGraph(const PoseGraph& graph) {
  const auto& vars = graph.variables();
  if (vars.empty()) throw std::invalid_argument("SE-Sync certificate: empty graph");
  const VariableKind kind = vars.front().kind;
  if (kind != VariableKind::kPose2 && kind != VariableKind::kPose3) {
    throw std::invalid_argument("SE-Sync certificate: only pose variables (no landmarks)");
  }
  for (const Variable& v : vars) {
    if (v.kind != kind) throw std::invalid_argument("SE-Sync certificate: poses of one dimension only");
  }
  const FactorKind between = kind == VariableKind::kPose2 ? FactorKind::kBetween2 : FactorKind::kBetween3;
  for (const Factor& f : graph.factors()) {
    if (f.kind != between) {
      throw std::invalid_argument("SE-Sync certificate: only relative-pose factors of the poses' dimension");
    }
  }
  return kind == VariableKind::kPose2 ? 2 : 3;
}

template <int D>
struct Problem {
  static constexpr int kRotDim = D == 2 ? 1 : 3;  // tangent dimension of SO(d)
  static constexpr int kP = D + kRotDim;          // tangent dimension of one pose
  static constexpr int kRes = D * D + D;          // residual rows of one edge
  using Rot = Eigen::Matrix<double, D, D>;
  using Vec = Eigen::Matrix<double, D, 1>;
  using RotVec = Eigen::Matrix<double, kRotDim, 1>;
  using Jac = Eigen::Matrix<double, kRes, kP>;
  using Res = Eigen::Matrix<double, kRes, 1>;

  struct Edge {
    int i = 0, j = 0;
    Rot rz;
    Vec tz;
    double kappa = 0.0, tau = 0.0;
  };
  struct State {
    std::vector<Vec> t;
    std::vector<Rot> r;
  };

  std::vector<Edge> edges;
  int n = 0;

  static Rot generator(int k) {
    Rot g = Rot::Zero();
    if constexpr (D == 2) {
      g(0, 1) = -1.0;
      g(1, 0) = 1.0;
    } else {
      g = skew(Eigen::Vector3d::Unit(k));
    }
    return g;
  }
  static Rot expRot(const RotVec& w) {
    if constexpr (D == 2) {
      return rotation2(w(0));
    } else {
      return expSO3(w).toRotationMatrix();
    }
  }

  Problem(const PoseGraph& graph, State& x) {
    const auto& vars = graph.variables();
    n = static_cast<int>(vars.size());
    x.t.resize(n);
    x.r.resize(n);
    for (int k = 0; k < n; ++k) {
      if constexpr (D == 2) {
        x.t[k] = vars[k].pose2.t;
        x.r[k] = rotation2(vars[k].pose2.theta);
      } else {
        x.t[k] = vars[k].pose3.t;
        x.r[k] = vars[k].pose3.q.normalized().toRotationMatrix();
      }
    }
    for (const Factor& f : graph.factors()) {
      Edge e;
      e.i = static_cast<int>(f.var[0]);
      e.j = static_cast<int>(f.var[1]);
      if constexpr (D == 2) {
        e.rz = rotation2(f.z2.theta);
        e.tz = f.z2.t;
      } else {
        e.rz = f.z3.q.normalized().toRotationMatrix();
        e.tz = f.z3.t;
      }
      const SeSyncWeights w = seSyncWeights(f);
      e.kappa = w.kappa;
      e.tau = w.tau;
      edges.push_back(e);
    }
  }

  // Whitened residual [sqrt(kappa) vec(R_j - R_i Rz); sqrt(tau) (t_j - t_i - R_i tz)]; f = |r|^2 summed.
  static Res residual(const Edge& e, const State& x) {
    Res r;
    const Rot dr = x.r[e.j] - x.r[e.i] * e.rz;
    r.template head<D * D>() = std::sqrt(e.kappa) * Eigen::Map<const Eigen::Matrix<double, D * D, 1>>(dr.data());
    r.template tail<D>() = std::sqrt(e.tau) * (x.t[e.j] - x.t[e.i] - x.r[e.i] * e.tz);
    return r;
  }

  double cost(const State& x) const {
    double f = 0.0;
    for (const Edge& e : edges) f += residual(e, x).squaredNorm();
    return f;
  }

  // Jacobians w.r.t. the pose tangents [delta t; delta w] with t <- t + delta t, R <- R Exp(delta w).
  static void jacobians(const Edge& e, const State& x, Jac& ji, Jac& jj) {
    ji.setZero();
    jj.setZero();
    const double sk = std::sqrt(e.kappa), st = std::sqrt(e.tau);
    ji.template block<D, D>(D * D, 0) = -st * Rot::Identity();
    jj.template block<D, D>(D * D, 0) = st * Rot::Identity();
    for (int k = 0; k < kRotDim; ++k) {
      const Rot g = generator(k);
      const Rot di = -sk * x.r[e.i] * g * e.rz;
      const Rot dj = sk * x.r[e.j] * g;
      ji.template block<D * D, 1>(0, D + k) = Eigen::Map<const Eigen::Matrix<double, D * D, 1>>(di.data());
      jj.template block<D * D, 1>(0, D + k) = Eigen::Map<const Eigen::Matrix<double, D * D, 1>>(dj.data());
      ji.template block<D, 1>(D * D, D + k) = -st * x.r[e.i] * g * e.tz;
    }
  }

  // Normal equations over poses 1..n-1 (pose 0 holds the gauge), upper triangle as triplets; full gradient
  // J^T r over all poses (half the gradient of f). Returns f.
  double linearize(const State& x, Triplets& h, Eigen::VectorXd& g) const {
    h.clear();
    g.setZero(static_cast<Eigen::Index>(kP) * n);
    const int m = kP * (n - 1);
    for (int c = 0; c < m; ++c) h.emplace_back(c, c, 0.0);  // keep the diagonal in the pattern
    double f = 0.0;
    Jac ji, jj;
    for (const Edge& e : edges) {
      const Res r = residual(e, x);
      f += r.squaredNorm();
      jacobians(e, x, ji, jj);
      g.template segment<kP>(kP * e.i) += ji.transpose() * r;
      g.template segment<kP>(kP * e.j) += jj.transpose() * r;
      const int oi = kP * (e.i - 1), oj = kP * (e.j - 1);
      auto add = [&](int ro, int co, const Eigen::Matrix<double, kP, kP>& b) {
        for (int c = 0; c < kP; ++c) {
          for (int rr = 0; rr < kP; ++rr) {
            if (ro + rr <= co + c) h.emplace_back(ro + rr, co + c, b(rr, c));
          }
        }
      };
      if (e.i > 0) add(oi, oi, ji.transpose() * ji);
      if (e.j > 0) add(oj, oj, jj.transpose() * jj);
      if (e.i > 0 && e.j > 0) {
        if (oi < oj) {
          add(oi, oj, ji.transpose() * jj);
        } else {
          add(oj, oi, jj.transpose() * ji);
        }
      }
    }
    return f;
  }

  State retract(const State& x, const Eigen::VectorXd& step) const {
    State y = x;
    for (int k = 1; k < n; ++k) {
      const auto s = step.template segment<kP>(kP * (k - 1));
      y.t[k] += s.template head<D>();
      y.r[k] = x.r[k] * expRot(s.template tail<kRotDim>());
    }
    return y;
  }

  // Riemannian Levenberg-Marquardt (Marquardt scaling, Nielsen's damping update) to a critical point of f.
  void refine(State& x, const CertificateOptions& opt, CertificateResult& res) const {
    Triplets trip;
    Eigen::VectorXd g;
    double f = linearize(x, trip, g);
    double weight_sum = 0.0;
    for (const Edge& e : edges) weight_sum += e.kappa + e.tau;
    const double gtol = opt.gradient_tolerance * std::sqrt(weight_sum);
    const int m = kP * (n - 1);
    if (m == 0 || !opt.refine) {
      res.gradient_norm = 2.0 * g.norm();
      res.refine_converged = res.gradient_norm <= gtol;
      return;
    }
    SpMat h(m, m);
    detail::SparseCholesky chol;
    double lambda = 1e-4, nu = 2.0;
    bool relinearized = true;
    std::vector<int> diag(m);
    for (int it = 0; it < opt.max_iterations; ++it) {
      if (relinearized) {
        h.setFromTriplets(trip.begin(), trip.end());
        h.makeCompressed();
        if (!chol.analyzed()) {
          chol.setPattern(m, std::vector<int>(h.outerIndexPtr(), h.outerIndexPtr() + m + 1),
                          std::vector<int>(h.innerIndexPtr(), h.innerIndexPtr() + h.nonZeros()));
          chol.analyze(/*natural_ordering=*/false);
        }
        for (int c = 0; c < m; ++c) diag[c] = h.outerIndexPtr()[c + 1] - 1;  // sorted rows: diagonal last
        relinearized = false;
        if (2.0 * g.tail(m).norm() <= gtol) {
          res.refine_converged = true;
          break;
        }
      }
      std::copy(h.valuePtr(), h.valuePtr() + h.nonZeros(), chol.values());
      for (int c = 0; c < m; ++c) chol.values()[diag[c]] += lambda * std::clamp(h.valuePtr()[diag[c]], 1e-6, 1e32);
      ++res.refine_iterations;
      if (!chol.factorize()) {
        lambda *= nu;
        nu *= 2.0;
        continue;
      }
      const Eigen::VectorXd rhs = -g.tail(m);
      Eigen::VectorXd step(m);
      chol.solve(rhs.data(), step.data());
      const double predicted = 2.0 * rhs.dot(step) - step.dot(h.selfadjointView<Eigen::Upper>() * step);
      const State trial = retract(x, step);
      const double f_new = cost(trial);
      if (predicted > 0.0 && f_new < f) {
        const double rho = (f - f_new) / predicted;
        const double decrease = f - f_new;
        x = trial;
        f = linearize(x, trip, g);
        relinearized = true;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        nu = 2.0;
        if (decrease <= opt.function_tolerance * f_new) {
          res.refine_converged = true;
          break;
        }
      } else {
        lambda *= nu;
        nu *= 2.0;
        if (lambda > 1e20) {  // no representable decrease left: converged to working precision
          res.refine_converged = true;
          break;
        }
      }
    }
    res.gradient_norm = 2.0 * g.norm();
  }

  // Index of t_k (column of Y) and of the first column of R_k.
  int tIdx(int k) const { return k; }
  int rIdx(int k) const { return n + D * k; }

  // Upper triangle of the data matrix M with f = tr(Y M Y^T).
  SpMat dataMatrix() const {
    const int nn = n + D * n;
    Triplets t;
    for (int c = 0; c < nn; ++c) t.emplace_back(c, c, 0.0);
    auto addBlock = [&](int ro, int co, const Eigen::MatrixXd& b) {  // b at (ro, co), mirrored if below diagonal
      for (int c = 0; c < b.cols(); ++c) {
        for (int r = 0; r < b.rows(); ++r) {
          const int gr = ro + r, gc = co + c;
          if (gr <= gc) t.emplace_back(gr, gc, b(r, c));
          else if (ro != co) t.emplace_back(gc, gr, b(r, c));
        }
      }
    };
    for (const Edge& e : edges) {
      // kappa |R_j - R_i Rz|^2: A = E_j - E_i Rz, kappa A A^T.
      addBlock(rIdx(e.i), rIdx(e.i), e.kappa * Rot::Identity());
      addBlock(rIdx(e.j), rIdx(e.j), e.kappa * Rot::Identity());
      addBlock(rIdx(e.i), rIdx(e.j), -e.kappa * e.rz);
      // tau |t_j - t_i - R_i tz|^2: b = e_j - e_i - E_i tz, tau b b^T.
      addBlock(tIdx(e.i), tIdx(e.i), Eigen::MatrixXd::Constant(1, 1, e.tau));
      addBlock(tIdx(e.j), tIdx(e.j), Eigen::MatrixXd::Constant(1, 1, e.tau));
      addBlock(tIdx(e.i), tIdx(e.j), Eigen::MatrixXd::Constant(1, 1, -e.tau));
      addBlock(tIdx(e.i), rIdx(e.i), e.tau * e.tz.transpose());
      addBlock(tIdx(e.j), rIdx(e.i), -e.tau * e.tz.transpose());
      addBlock(rIdx(e.i), rIdx(e.i), e.tau * e.tz * e.tz.transpose());
    }
    SpMat m(nn, nn);
    m.setFromTriplets(t.begin(), t.end());
    m.makeCompressed();
    return m;
  }

  // Y^T (N x d): rows t_k^T, then R_k^T.
  Eigen::MatrixXd yTransposed(const State& x) const {
    Eigen::MatrixXd yt(n + D * n, D);
    for (int k = 0; k < n; ++k) {
      yt.row(tIdx(k)) = x.t[k].transpose();
      yt.block(rIdx(k), 0, D, D) = x.r[k].transpose();
    }
    return yt;
  }
};

// Tests S + sigma I for positive definiteness with one symbolic analysis and numeric refactorizations.
class PsdTest {
 public:
  explicit PsdTest(const SpMat& s) : base_(s.valuePtr(), s.valuePtr() + s.nonZeros()) {
    const int n = static_cast<int>(s.cols());
    chol_.setPattern(n, std::vector<int>(s.outerIndexPtr(), s.outerIndexPtr() + n + 1),
                     std::vector<int>(s.innerIndexPtr(), s.innerIndexPtr() + s.nonZeros()));
    // Supernodal = LL^T, which stops at the first non-positive pivot; CHOLMOD's simplicial default is LDL^T,
    // which factorizes indefinite matrices without complaint.
    chol_.analyze(/*natural_ordering=*/false, /*kind=*/2);
    diag_.resize(n);
    for (int c = 0; c < n; ++c) diag_[c] = s.outerIndexPtr()[c + 1] - 1;
  }
  bool positiveDefinite(double sigma) {
    std::copy(base_.begin(), base_.end(), chol_.values());
    for (int d : diag_) chol_.values()[d] += sigma;
    ++factorizations_;
    return chol_.factorize();
  }
  /// x <- (S + sigma I)^-1 b, after a successful positiveDefinite(sigma).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    x.resize(b.size());
    chol_.solve(b.data(), x.data());
  }
  int factorizations() const { return factorizations_; }

 private:
  detail::SparseCholesky chol_;
  std::vector<double> base_;
  std::vector<int> diag_;
  int factorizations_ = 0;
};

template <int D>
CertificateResult certify(const PoseGraph& graph, const CertificateOptions& opt, PoseGraph* refined) {
  using P = Problem<D>;
  CertificateResult res;
  typename P::State x;
  const P prob(graph, x);
  res.dimension = D;
  res.poses = static_cast<std::size_t>(prob.n);
  res.edges = prob.edges.size();
  res.objective_input = prob.cost(x);
  // (a) critical point of f.
  prob.refine(x, opt, res);
  res.objective = prob.cost(x);

  // (b) multipliers and certificate matrix S = M - blockdiag(0, Lambda_1 .. Lambda_n) (upper triangle).
  SpMat s = prob.dataMatrix();
  const Eigen::MatrixXd yt = prob.yTransposed(x);
  const Eigen::MatrixXd myt = s.template selfadjointView<Eigen::Upper>() * yt;  // (Y M)^T
  Eigen::MatrixXd lambda_yt = Eigen::MatrixXd::Zero(yt.rows(), D);             // (Y Lambda)^T
  res.dual_bound = 0.0;
  for (int k = 0; k < prob.n; ++k) {
    const int o = prob.rIdx(k);
    const typename P::Rot ymr = myt.block(o, 0, D, D).transpose();  // (Y M)_{R_k}
    const typename P::Rot rm = x.r[k].transpose() * ymr;
    const typename P::Rot lam = 0.5 * (rm + rm.transpose());
    res.dual_bound += lam.trace();
    lambda_yt.block(o, 0, D, D) = (x.r[k] * lam).transpose();
    for (int c = 0; c < D; ++c) {
      for (int r = 0; r <= c; ++r) s.coeffRef(o + r, o + c) -= lam(r, c);
    }
  }
  s.makeCompressed();
  res.stationarity = (myt - lambda_yt).norm() / std::max(myt.norm(), std::numeric_limits<double>::min());

  // (c) S + eta I positive definite <=> lambda_min(S) > -eta.
  double max_diag = 0.0, gersh = 0.0;
  {
    Eigen::VectorXd row_abs = Eigen::VectorXd::Zero(s.cols());
    for (int c = 0; c < s.outerSize(); ++c) {
      for (SpMat::InnerIterator it(s, c); it; ++it) {
        row_abs(it.row()) += std::abs(it.value());
        if (it.row() != it.col()) row_abs(it.col()) += std::abs(it.value());
        else max_diag = std::max(max_diag, it.value());
      }
    }
    gersh = row_abs.maxCoeff();  // |lambda(S)| <= max row sum of |S|
  }
  res.eta = opt.eta_relative * std::max(max_diag, std::numeric_limits<double>::min());
  double y_norm2 = static_cast<double>(D) * prob.n;  // |Y|_F^2 with centered translations (|R_i|_F^2 = d)
  {
    typename P::Vec mean = P::Vec::Zero();
    for (const auto& t : x.t) mean += t;
    mean /= prob.n;
    for (const auto& t : x.t) y_norm2 += (t - mean).squaredNorm();
  }
  res.dual_bound_slack = res.eta * y_norm2;
  PsdTest psd(s);
  res.certified = psd.positiveDefinite(res.eta);

  // Known null space of S at a critical point: the rows of Y and the translation gauge [1 .. 1, 0 .. 0].
  Eigen::MatrixXd known(yt.rows(), D + 1);
  known.leftCols(D) = yt;
  known.col(D).setZero();
  known.col(D).head(prob.n).setOnes();
  const Eigen::MatrixXd basis = Eigen::HouseholderQR<Eigen::MatrixXd>(known).householderQ() *
                                Eigen::MatrixXd::Identity(known.rows(), D + 1);
  const Eigen::MatrixXd sb = s.template selfadjointView<Eigen::Upper>() * basis;
  const Eigen::MatrixXd rayleigh = basis.transpose() * sb;
  const double null_upper = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(rayleigh).eigenvalues().minCoeff();

  if (res.certified) {
    res.lambda_min_lower = -res.eta;
    res.lambda_min_upper = null_upper;
    res.lambda_min = null_upper;
    // Deflated inverse iteration on (S + eta I)^-1 for the smallest eigenvalue off the known null space.
    std::mt19937 rng(7);
    std::normal_distribution<double> nd;
    Eigen::VectorXd v(s.cols()), w;
    for (Eigen::Index k = 0; k < v.size(); ++k) v(k) = nd(rng);
    double q_prev = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 100; ++it) {
      v -= basis * (basis.transpose() * v);
      v.normalize();
      const double q = v.dot(s.template selfadjointView<Eigen::Upper>() * v);
      res.lambda_deflated = q;
      if (std::abs(q - q_prev) <= 1e-6 * std::abs(q)) break;
      q_prev = q;
      psd.solve(v, w);
      v = w;
    }
    // Tighten the lower end: the smallest shift eta / 10^k that still factorizes bounds lambda_min from below
    // (and with it the tolerance's slack in the dual bound). Not below 1e-14 max S_ii: smaller shifts are
    // within the rounding of the factorization (a factorization then "succeeds" below the Rayleigh quotient).
    double sigma = res.eta;
    const double floor_shift = 1e-14 * max_diag;
    while (0.1 * sigma >= floor_shift && psd.positiveDefinite(0.1 * sigma)) sigma *= 0.1;
    res.lambda_min_lower = -sigma;
    res.dual_bound_slack = sigma * y_norm2;
  } else {
    // Bisection on the shift: positive definite at hi, not at lo.
    double lo = res.eta, hi = std::max(gersh * (1.0 + 1e-9) + res.eta, 2.0 * res.eta);
    for (int k = 0; k < 60 && !psd.positiveDefinite(hi); ++k) {
      lo = hi;
      hi *= 2.0;
    }
    while (hi - lo > opt.lambda_relative_precision * hi) {
      const double mid = hi > 4.0 * lo ? std::sqrt(lo * hi) : 0.5 * (lo + hi);
      if (psd.positiveDefinite(mid)) hi = mid;
      else lo = mid;
    }
    res.lambda_min_lower = -hi;
    res.lambda_min_upper = -lo;
    res.lambda_min = -0.5 * (lo + hi);
  }
  res.factorizations = psd.factorizations();

  if (refined != nullptr) {
    *refined = graph;
    std::vector<Variable> vals = graph.variables();
    for (int k = 0; k < prob.n; ++k) {
      if constexpr (D == 2) {
        vals[k].pose2.t = x.t[k];
        vals[k].pose2.theta = std::atan2(x.r[k](1, 0), x.r[k](0, 0));
      } else {
        vals[k].pose3.t = x.t[k];
        vals[k].pose3.q = Eigen::Quaterniond(Eigen::Matrix3d(x.r[k])).normalized();
      }
    }
    refined->setValues(vals);
  }
  return res;
}

}  // namespace

double seSyncObjective(const PoseGraph& graph) {
  if (checkGraph(graph) == 2) {
    Problem<2>::State x;
    return Problem<2>(graph, x).cost(x);
  }
  Problem<3>::State x;
  return Problem<3>(graph, x).cost(x);
}

CertificateResult certifyGlobalOptimum(const PoseGraph& graph, const CertificateOptions& options,
                                       PoseGraph* refined) {
  const auto t0 = std::chrono::steady_clock::now();
  CertificateResult res =
      checkGraph(graph) == 2 ? certify<2>(graph, options, refined) : certify<3>(graph, options, refined);
  res.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace cairn::graph_slam
