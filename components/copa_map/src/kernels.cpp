#include "cairn/copa_map/kernels.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cairn::copa_map {
namespace {

constexpr double kSqrt5 = 2.23606797749978969641;
constexpr double kPi = 3.14159265358979323846;
// Below this many kernel entries threads cost more than they save (busy CPUs make spinning threads slow).
constexpr Eigen::Index kParallelMin = 40000;

// 1D Matérn-5/2 with unit variance (eq. 4.9) and its derivative w.r.t. log l.
inline void matern52(double d, double l, double& k, double& dk_dlogl) {
  const double r = std::abs(d) / l;
  const double e = std::exp(-kSqrt5 * r);
  k = (1.0 + kSqrt5 * r + 5.0 / 3.0 * r * r) * e;
  dk_dlogl = 5.0 / 3.0 * r * r * (1.0 + kSqrt5 * r) * e;
}

// d k / d Δ of the unit-variance 1D Matérn-5/2 (eq. 4.9): -(5/3) (Δ/l²) (1 + √5 r) e^{-√5 r}, r = |Δ|/l.
inline double matern52Slope(double d, double l) {
  const double r = std::abs(d) / l;
  return -5.0 / 3.0 * d / (l * l) * (1.0 + kSqrt5 * r) * std::exp(-kSqrt5 * r);
}

// Accumulates Σ_ij G_ij ∂k/∂Δ_ij (Δ = x1_i - x2_j) into rows i of d1 (+) and rows j of d2 (-); `slope` returns
// the three components of ∂k/∂Δ for one pair. Parallel over the columns j (each thread owns its rows of d2 and
// a private copy of d1).
template <class Slope>
void accumulateInputGrads(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2, const Eigen::MatrixXd& G,
                          Eigen::MatrixXd* d1, Eigen::MatrixXd* d2, Slope&& slope) {
  const Eigen::Index n1 = X1.rows(), n2 = X2.rows();
  if (d2) *d2 = Eigen::MatrixXd::Zero(n2, 3);
  std::vector<Eigen::MatrixXd> parts(static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel if (n1 * n2 > kParallelMin)
  {
    Eigen::MatrixXd& acc = parts[static_cast<std::size_t>(omp_get_thread_num())];
    if (d1) acc = Eigen::MatrixXd::Zero(n1, 3);
#pragma omp for schedule(dynamic, 32)
    for (Eigen::Index j = 0; j < n2; ++j) {
      Eigen::RowVector3d dj = Eigen::RowVector3d::Zero();
      for (Eigen::Index i = 0; i < n1; ++i) {
        const double gij = G(i, j);
        if (gij == 0.0) continue;
        const Eigen::RowVector3d s = gij * slope(X1.row(i), X2.row(j));
        if (d1) acc.row(i) += s;
        dj -= s;
      }
      if (d2) d2->row(j) = dj;
    }
  }
  if (d1) {
    *d1 = Eigen::MatrixXd::Zero(n1, 3);
    for (const auto& p : parts)
      if (p.rows() == n1) *d1 += p;
  }
}

// Thread-local partial sums reduced at the end (gradients).
Eigen::VectorXd reduce(const std::vector<Eigen::VectorXd>& parts, int n) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  for (const auto& p : parts) g += p;
  return g;
}

// Distinct values of one input column and, per row, the index of its value (exact equality). Gridded data
// (the gridifier's cell centres and bins, copa-map's inducing points on the same grid) repeat few values per
// axis: the ATC training split has 49 x1, 44 x2 and 120 t values in 76,456 rows.
struct AxisValues {
  std::vector<double> v;
  std::vector<int> id;
};

AxisValues distinctValues(const Eigen::MatrixXd& X, Eigen::Index col) {
  const Eigen::Index n = X.rows();
  std::vector<int> order(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return X(a, col) < X(b, col); });
  AxisValues a;
  a.id.resize(static_cast<std::size_t>(n));
  for (const int r : order) {
    if (a.v.empty() || X(r, col) != a.v.back()) a.v.push_back(X(r, col));
    a.id[static_cast<std::size_t>(r)] = static_cast<int>(a.v.size()) - 1;
  }
  return a;
}

// Per-axis value pairs of two input sets: the factors of a product kernel along one axis depend only on the pair
// (value in X1, value in X2), so they can be tabulated over the distinct pairs and looked up per entry.
struct AxisPairs {
  AxisValues a[3], b[3];
  // Table entries over all three axes (each axis: distinct X1 values x distinct X2 values).
  double tableSize() const {
    double s = 0;
    for (int d = 0; d < 3; ++d) s += static_cast<double>(a[d].v.size()) * static_cast<double>(b[d].v.size());
    return s;
  }
};

AxisPairs axisPairs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) {
  AxisPairs p;
  for (int d = 0; d < 3; ++d) {
    p.a[d] = distinctValues(X1, d);
    p.b[d] = distinctValues(X2, d);
  }
  return p;
}

// Tables pay off when they hold far fewer entries than the kernel matrix (each table entry costs the
// transcendental functions a direct entry would cost).
bool tablesPay(const AxisPairs& p, Eigen::Index n1, Eigen::Index n2) {
  return p.tableSize() <= 0.25 * static_cast<double>(n1) * static_cast<double>(n2);
}

}  // namespace

SpatioTemporalKernel::SpatioTemporalKernel(double ls1, double ls2, std::vector<PeriodicComponent> comps)
    : ls1_(ls1), ls2_(ls2), comps_(std::move(comps)) {
  if (!(ls1 > 0) || !(ls2 > 0)) throw std::invalid_argument("SpatioTemporalKernel: length scales must be > 0");
  for (const auto& c : comps_)
    if (!(c.variance > 0) || !(c.period > 0) || !(c.lengthscale > 0))
      throw std::invalid_argument("SpatioTemporalKernel: periodic parameters must be > 0");
}

Eigen::VectorXd SpatioTemporalKernel::params() const {
  Eigen::VectorXd p(numParams());
  p[0] = std::log(ls1_);
  p[1] = std::log(ls2_);
  for (std::size_t i = 0; i < comps_.size(); ++i) {
    p[2 + 3 * i] = std::log(comps_[i].variance);
    p[3 + 3 * i] = std::log(comps_[i].period);
    p[4 + 3 * i] = std::log(comps_[i].lengthscale);
  }
  return p;
}

void SpatioTemporalKernel::setParams(const Eigen::VectorXd& p) {
  if (p.size() != numParams()) throw std::invalid_argument("SpatioTemporalKernel::setParams: wrong size");
  ls1_ = std::exp(p[0]);
  ls2_ = std::exp(p[1]);
  for (std::size_t i = 0; i < comps_.size(); ++i) {
    comps_[i].variance = std::exp(p[2 + 3 * i]);
    comps_[i].period = std::exp(p[3 + 3 * i]);
    comps_[i].lengthscale = std::exp(p[4 + 3 * i]);
  }
}

std::vector<std::string> SpatioTemporalKernel::paramNames() const {
  std::vector<std::string> n{"log_lengthscale_x1", "log_lengthscale_x2"};
  for (std::size_t i = 0; i < comps_.size(); ++i) {
    n.push_back("log_periodic_variance_" + std::to_string(i));
    n.push_back("log_period_" + std::to_string(i));
    n.push_back("log_periodic_lengthscale_" + std::to_string(i));
  }
  return n;
}

Eigen::VectorXd SpatioTemporalKernel::lowerBounds() const {
  Eigen::VectorXd b(numParams());
  b[0] = b[1] = std::log(min_lengthscale);
  for (std::size_t i = 0; i < comps_.size(); ++i) {
    b[2 + 3 * i] = std::log(1e-6);
    b[3 + 3 * i] = std::log(min_period);
    b[4 + 3 * i] = std::log(0.05);
  }
  return b;
}

Eigen::VectorXd SpatioTemporalKernel::upperBounds() const {
  Eigen::VectorXd b(numParams());
  b[0] = b[1] = std::log(max_lengthscale);
  for (std::size_t i = 0; i < comps_.size(); ++i) {
    b[2 + 3 * i] = std::log(100.0);
    b[3 + 3 * i] = std::log(max_period);
    b[4 + 3 * i] = std::log(100.0);
  }
  return b;
}

bool SpatioTemporalKernel::valueTablesApply(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) {
  return X1.cols() == 3 && X2.cols() == 3 && tablesPay(axisPairs(X1, X2), X1.rows(), X2.rows());
}

namespace {

// Eq. 4.10 summed over the components for one time difference.
double periodicSum(const std::vector<PeriodicComponent>& comps, double dt) {
  double kt = 0.0;
  for (const auto& c : comps) {
    const double s = std::sin(kPi * dt / c.period);
    kt += c.variance * std::exp(-0.5 * s * s / (c.lengthscale * c.lengthscale));  // eq. 4.10
  }
  return kt;
}

// One component of eq. 4.10 at time difference dt and its derivatives by log σ², log p and log l (the first
// equals the value): shared by the direct and the table path of gradK.
struct PeriodicTerm {
  double value, d_log_period, d_log_lengthscale;
};

PeriodicTerm periodicTerm(const PeriodicComponent& c, double dt) {
  const double arg = kPi * dt / c.period, s = std::sin(arg);
  const double l2 = c.lengthscale * c.lengthscale;
  const double v = c.variance * std::exp(-0.5 * s * s / l2);  // eq. 4.10
  return {v, v * s * std::cos(arg) * arg / l2, v * s * s / l2};
}

}  // namespace

Eigen::MatrixXd SpatioTemporalKernel::K(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) const {
  const Eigen::Index n1 = X1.rows(), n2 = X2.rows();
  Eigen::MatrixXd out(n1, n2);
  if (use_value_tables && X1.cols() == 3 && X2.cols() == 3) {
    const AxisPairs p = axisPairs(X1, X2);
    if (tablesPay(p, n1, n2)) {
      // Same formula and the same floating-point operations per factor as the direct loop below, evaluated once
      // per distinct value pair: the result is bit-identical (tested) at a fraction of the sin/exp calls.
      Eigen::MatrixXd T[3];
      for (int d = 0; d < 3; ++d) {
        const auto &va = p.a[d].v, &vb = p.b[d].v;
        T[d].resize(static_cast<Eigen::Index>(va.size()), static_cast<Eigen::Index>(vb.size()));
        for (std::size_t jb = 0; jb < vb.size(); ++jb)
          for (std::size_t ia = 0; ia < va.size(); ++ia) {
            const double diff = va[ia] - vb[jb];
            double k, tmp;
            if (d == 2)
              k = periodicSum(comps_, diff);
            else
              matern52(diff, d == 0 ? ls1_ : ls2_, k, tmp);
            T[d](static_cast<Eigen::Index>(ia), static_cast<Eigen::Index>(jb)) = k;
          }
      }
#pragma omp parallel for schedule(static) if (n1 * n2 > kParallelMin)
      for (Eigen::Index j = 0; j < n2; ++j) {
        const auto uj = static_cast<std::size_t>(j);
        const double* c1 = T[0].col(p.b[0].id[uj]).data();
        const double* c2 = T[1].col(p.b[1].id[uj]).data();
        const double* ct = T[2].col(p.b[2].id[uj]).data();
        const int *i1 = p.a[0].id.data(), *i2 = p.a[1].id.data(), *it = p.a[2].id.data();
        double* o = out.col(j).data();
        for (Eigen::Index i = 0; i < n1; ++i) o[i] = c1[i1[i]] * c2[i2[i]] * ct[it[i]];  // eq. 4.8
      }
      return out;
    }
  }
#pragma omp parallel for schedule(static) if (n1 * n2 > kParallelMin)
  for (Eigen::Index j = 0; j < n2; ++j) {
    for (Eigen::Index i = 0; i < n1; ++i) {
      double k1, k2, tmp;
      matern52(X1(i, 0) - X2(j, 0), ls1_, k1, tmp);
      matern52(X1(i, 1) - X2(j, 1), ls2_, k2, tmp);
      out(i, j) = k1 * k2 * periodicSum(comps_, X1(i, 2) - X2(j, 2));  // eq. 4.8
    }
  }
  return out;
}

Eigen::VectorXd SpatioTemporalKernel::Kdiag(const Eigen::MatrixXd& X) const {
  double kt = 0.0;
  for (const auto& c : comps_) kt += c.variance;
  return Eigen::VectorXd::Constant(X.rows(), kt);
}

// gradK over per-axis value tables (see K): the Matérn factors and their log-length-scale derivatives per distinct
// (x1, x1') and (x2, x2') pair, the periodic sum and the three derivatives of each component per distinct (t, t')
// pair. Per column j the weights g_ij k1 k2 are first summed per distinct t_i, then contracted with the periodic
// tables, so the per-entry work no longer grows with the number of components.
namespace {

void gradKTables(const SpatioTemporalKernel& kern, const AxisPairs& p, const Eigen::MatrixXd& G,
                 std::vector<Eigen::VectorXd>& parts) {
  const std::vector<PeriodicComponent>& comps = kern.components();
  const double ls[2] = {kern.lengthscale1(), kern.lengthscale2()};
  const std::size_t nc = comps.size();
  const auto size = [&](int d) {
    return std::pair<Eigen::Index, Eigen::Index>(static_cast<Eigen::Index>(p.a[d].v.size()),
                                                 static_cast<Eigen::Index>(p.b[d].v.size()));
  };
  Eigen::MatrixXd Ks[2], Ds[2];
  for (int d = 0; d < 2; ++d) {
    const auto [ua, ub] = size(d);
    Ks[d].resize(ua, ub);
    Ds[d].resize(ua, ub);
    for (Eigen::Index jb = 0; jb < ub; ++jb)
      for (Eigen::Index ia = 0; ia < ua; ++ia)
        matern52(p.a[d].v[static_cast<std::size_t>(ia)] - p.b[d].v[static_cast<std::size_t>(jb)],
                 ls[d], Ks[d](ia, jb), Ds[d](ia, jb));
  }
  const auto [uta, utb] = size(2);
  Eigen::MatrixXd Kt = Eigen::MatrixXd::Zero(uta, utb);
  // Per component: ∂/∂log σ², ∂/∂log p, ∂/∂log l of eq. 4.10 (without the spatial factor).
  std::vector<Eigen::MatrixXd> Pv(nc, Eigen::MatrixXd(uta, utb)), Pp(nc, Eigen::MatrixXd(uta, utb)),
      Pl(nc, Eigen::MatrixXd(uta, utb));
  for (Eigen::Index jb = 0; jb < utb; ++jb)
    for (Eigen::Index ia = 0; ia < uta; ++ia) {
      const double dt = p.a[2].v[static_cast<std::size_t>(ia)] - p.b[2].v[static_cast<std::size_t>(jb)];
      for (std::size_t c = 0; c < nc; ++c) {
        const PeriodicTerm pt = periodicTerm(comps[c], dt);
        Kt(ia, jb) += pt.value;
        Pv[c](ia, jb) = pt.value;
        Pp[c](ia, jb) = pt.d_log_period;
        Pl[c](ia, jb) = pt.d_log_lengthscale;
      }
    }
  const Eigen::Index n1 = G.rows(), n2 = G.cols();
#pragma omp parallel if (n1 * n2 > kParallelMin)
  {
    Eigen::VectorXd& acc = parts[static_cast<std::size_t>(omp_get_thread_num())];
    Eigen::VectorXd H(uta);
    const int *i1 = p.a[0].id.data(), *i2 = p.a[1].id.data(), *it = p.a[2].id.data();
#pragma omp for schedule(dynamic, 32)
    for (Eigen::Index j = 0; j < n2; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      const Eigen::Index b1 = p.b[0].id[uj], b2 = p.b[1].id[uj], bt = p.b[2].id[uj];
      const double *k1c = Ks[0].col(b1).data(), *d1c = Ds[0].col(b1).data();
      const double *k2c = Ks[1].col(b2).data(), *d2c = Ds[1].col(b2).data(), *ktc = Kt.col(bt).data();
      const double* g = G.col(j).data();
      H.setZero();
      double a0 = 0, a1 = 0;
      for (Eigen::Index i = 0; i < n1; ++i) {
        const double gij = g[i];
        if (gij == 0.0) continue;
        const double k1 = k1c[i1[i]], k2 = k2c[i2[i]], kt = ktc[it[i]];
        a0 += gij * d1c[i1[i]] * k2 * kt;
        a1 += gij * k1 * d2c[i2[i]] * kt;
        H[it[i]] += gij * k1 * k2;
      }
      acc[0] += a0;
      acc[1] += a1;
      for (std::size_t c = 0; c < nc; ++c) {
        acc[2 + 3 * static_cast<Eigen::Index>(c)] += H.dot(Pv[c].col(bt));  // ∂/∂log σ²
        acc[3 + 3 * static_cast<Eigen::Index>(c)] += H.dot(Pp[c].col(bt));  // ∂/∂log p
        acc[4 + 3 * static_cast<Eigen::Index>(c)] += H.dot(Pl[c].col(bt));  // ∂/∂log l
      }
    }
  }
}

}  // namespace

Eigen::VectorXd SpatioTemporalKernel::gradK(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                                            const Eigen::MatrixXd& G) const {
  const int np = numParams();
  const Eigen::Index n1 = X1.rows(), n2 = X2.rows();
  std::vector<Eigen::VectorXd> parts(static_cast<std::size_t>(omp_get_max_threads()),
                                     Eigen::VectorXd::Zero(np));
  if (use_value_tables && X1.cols() == 3 && X2.cols() == 3) {
    const AxisPairs p = axisPairs(X1, X2);
    if (tablesPay(p, n1, n2)) {
      gradKTables(*this, p, G, parts);
      return reduce(parts, np);
    }
  }
#pragma omp parallel if (n1 * n2 > kParallelMin)
  {
    Eigen::VectorXd& acc = parts[static_cast<std::size_t>(omp_get_thread_num())];
    std::vector<PeriodicTerm> pt(comps_.size());
#pragma omp for schedule(dynamic, 32)
    for (Eigen::Index j = 0; j < n2; ++j) {
      for (Eigen::Index i = 0; i < n1; ++i) {
        const double gij = G(i, j);
        if (gij == 0.0) continue;
        double k1, d1, k2, d2;
        matern52(X1(i, 0) - X2(j, 0), ls1_, k1, d1);
        matern52(X1(i, 1) - X2(j, 1), ls2_, k2, d2);
        const double dt = X1(i, 2) - X2(j, 2);
        double kt = 0.0;
        for (std::size_t c = 0; c < comps_.size(); ++c) {
          pt[c] = periodicTerm(comps_[c], dt);
          kt += pt[c].value;
        }
        acc[0] += gij * d1 * k2 * kt;
        acc[1] += gij * k1 * d2 * kt;
        const double ks = gij * k1 * k2;
        for (std::size_t c = 0; c < comps_.size(); ++c) {
          acc[2 + 3 * c] += ks * pt[c].value;              // ∂/∂log σ²
          acc[3 + 3 * c] += ks * pt[c].d_log_period;       // ∂/∂log p
          acc[4 + 3 * c] += ks * pt[c].d_log_lengthscale;  // ∂/∂log l
        }
      }
    }
  }
  return reduce(parts, np);
}

Eigen::VectorXd SpatioTemporalKernel::gradKdiag(const Eigen::MatrixXd& X, const Eigen::VectorXd& g) const {
  (void)X;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(numParams());
  const double s = g.sum();
  for (std::size_t c = 0; c < comps_.size(); ++c) out[2 + 3 * c] = s * comps_[c].variance;
  return out;
}

void SpatioTemporalKernel::gradInputs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                                      const Eigen::MatrixXd& G, Eigen::MatrixXd* d1, Eigen::MatrixXd* d2) const {
  accumulateInputGrads(X1, X2, G, d1, d2, [this](const auto& a, const auto& b) {
    const double dx1 = a(0) - b(0), dx2 = a(1) - b(1), dt = a(2) - b(2);
    double k1, k2, tmp;
    matern52(dx1, ls1_, k1, tmp);
    matern52(dx2, ls2_, k2, tmp);
    double kt = 0.0, dkt = 0.0;
    for (const auto& c : comps_) {
      const double arg = kPi * dt / c.period, sn = std::sin(arg);
      const double l2 = c.lengthscale * c.lengthscale;
      const double pc = c.variance * std::exp(-0.5 * sn * sn / l2);
      kt += pc;
      dkt -= pc * sn * std::cos(arg) * kPi / (c.period * l2);  // d/dΔt of eq. 4.10
    }
    return Eigen::RowVector3d(matern52Slope(dx1, ls1_) * k2 * kt, k1 * matern52Slope(dx2, ls2_) * kt, k1 * k2 * dkt);
  });
}

RbfKernel::RbfKernel(double variance, Eigen::Vector3d lengthscales) : var_(variance), ls_(lengthscales) {
  if (!(variance > 0) || !(lengthscales.minCoeff() > 0))
    throw std::invalid_argument("RbfKernel: variance and length scales must be > 0");
}

Eigen::VectorXd RbfKernel::params() const {
  Eigen::VectorXd p(4);
  p << std::log(var_), std::log(ls_[0]), std::log(ls_[1]), std::log(ls_[2]);
  return p;
}

void RbfKernel::setParams(const Eigen::VectorXd& p) {
  if (p.size() != 4) throw std::invalid_argument("RbfKernel::setParams: wrong size");
  var_ = std::exp(p[0]);
  for (int d = 0; d < 3; ++d) ls_[d] = std::exp(p[1 + d]);
}

std::vector<std::string> RbfKernel::paramNames() const {
  return {"log_variance", "log_lengthscale_x1", "log_lengthscale_x2", "log_lengthscale_t"};
}

Eigen::VectorXd RbfKernel::lowerBounds() const {
  Eigen::VectorXd b(4);
  b << std::log(1e-4), std::log(0.05), std::log(0.05), std::log(0.05);
  return b;
}

Eigen::VectorXd RbfKernel::upperBounds() const {
  Eigen::VectorXd b(4);
  b << std::log(1e3), std::log(1e4), std::log(1e4), std::log(1e5);
  return b;
}

Eigen::MatrixXd RbfKernel::K(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) const {
  const Eigen::Index n1 = X1.rows(), n2 = X2.rows();
  Eigen::MatrixXd out(n1, n2);
  const Eigen::Vector3d il = ls_.cwiseInverse();
#pragma omp parallel for schedule(static) if (n1 * n2 > kParallelMin)
  for (Eigen::Index j = 0; j < n2; ++j)
    for (Eigen::Index i = 0; i < n1; ++i) {
      double q = 0.0;
      for (int d = 0; d < 3; ++d) {
        const double u = (X1(i, d) - X2(j, d)) * il[d];
        q += u * u;
      }
      out(i, j) = var_ * std::exp(-0.5 * q);  // eq. 4.11
    }
  return out;
}

Eigen::VectorXd RbfKernel::Kdiag(const Eigen::MatrixXd& X) const {
  return Eigen::VectorXd::Constant(X.rows(), var_);
}

Eigen::VectorXd RbfKernel::gradK(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                                 const Eigen::MatrixXd& G) const {
  const Eigen::Index n1 = X1.rows(), n2 = X2.rows();
  const Eigen::Vector3d il = ls_.cwiseInverse();
  std::vector<Eigen::VectorXd> parts(static_cast<std::size_t>(omp_get_max_threads()), Eigen::VectorXd::Zero(4));
#pragma omp parallel if (n1 * n2 > kParallelMin)
  {
    Eigen::VectorXd& acc = parts[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(dynamic, 32)
    for (Eigen::Index j = 0; j < n2; ++j)
      for (Eigen::Index i = 0; i < n1; ++i) {
        double u[3], q = 0.0;
        for (int d = 0; d < 3; ++d) {
          u[d] = (X1(i, d) - X2(j, d)) * il[d];
          q += u[d] * u[d];
        }
        if (G(i, j) == 0.0) continue;
        const double k = G(i, j) * var_ * std::exp(-0.5 * q);
        acc[0] += k;
        for (int d = 0; d < 3; ++d) acc[1 + d] += k * u[d] * u[d];
      }
  }
  return reduce(parts, 4);
}

Eigen::VectorXd RbfKernel::gradKdiag(const Eigen::MatrixXd& X, const Eigen::VectorXd& g) const {
  (void)X;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(4);
  out[0] = g.sum() * var_;
  return out;
}

void RbfKernel::gradInputs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2, const Eigen::MatrixXd& G,
                           Eigen::MatrixXd* d1, Eigen::MatrixXd* d2) const {
  const Eigen::Vector3d il2 = ls_.cwiseInverse().cwiseAbs2();
  accumulateInputGrads(X1, X2, G, d1, d2, [this, &il2](const auto& a, const auto& b) {
    const Eigen::RowVector3d d = a - b;
    const double k = var_ * std::exp(-0.5 * d.cwiseAbs2().dot(il2.transpose()));
    return Eigen::RowVector3d(-k * d.cwiseProduct(il2.transpose()));
  });
}

std::unique_ptr<Kernel> makeKernel(const std::string& type, const Eigen::VectorXd& params) {
  if (type == "rbf_ard3") {
    auto k = std::make_unique<RbfKernel>(1.0, Eigen::Vector3d::Ones());
    k->setParams(params);
    return k;
  }
  if (type == "matern52x2_periodic_sum") {
    if (params.size() < 2 || (params.size() - 2) % 3 != 0)
      throw std::invalid_argument("makeKernel: bad parameter count for " + type);
    auto k = std::make_unique<SpatioTemporalKernel>(
        1.0, 1.0, std::vector<PeriodicComponent>(static_cast<std::size_t>((params.size() - 2) / 3)));
    k->setParams(params);
    return k;
  }
  throw std::invalid_argument("makeKernel: unknown kernel type '" + type + "'");
}

}  // namespace cairn::copa_map
