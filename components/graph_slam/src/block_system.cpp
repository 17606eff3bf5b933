#include "block_system.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "cairn/graph_slam/factors.hpp"

namespace cairn::graph_slam::detail {

void BlockSystem::build(const PoseGraph& graph, std::optional<std::size_t> gauge, int ordering,
                        int factorization, double nd_min_flops_per_block, bool reuse_ordering,
                        double reuse_fill_tolerance) {
  const auto& vars = graph.variables();
  const auto& factors = graph.factors();
  const std::size_t nv = vars.size();

  // Active variables become blocks.
  std::vector<int> block_of(nv, -1);
  std::vector<std::size_t> var_of_block;
  for (std::size_t v = 0; v < nv; ++v) {
    if (vars[v].fixed || (gauge && *gauge == v)) continue;
    block_of[v] = static_cast<int>(var_of_block.size());
    var_of_block.push_back(v);
  }
  const int nb = static_cast<int>(var_of_block.size());

  // Block adjacency (both triangles, no diagonal), sorted and unique.
  std::vector<std::vector<int>> adj(nb);
  for (const Factor& f : factors) {
    if (arity(f.kind) != 2) continue;
    const int a = block_of[f.var[0]], b = block_of[f.var[1]];
    if (a < 0 || b < 0 || a == b) continue;
    adj[a].push_back(b);
    adj[b].push_back(a);
  }
  std::vector<int> ap(nb + 1, 0), ai;
  for (int b = 0; b < nb; ++b) {
    auto& l = adj[b];
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    ap[b + 1] = ap[b] + static_cast<int>(l.size());
  }
  ai.reserve(ap[nb]);
  for (int b = 0; b < nb; ++b) ai.insert(ai.end(), adj[b].begin(), adj[b].end());

  // Fill-reducing ordering on the block graph (one node per variable, so the ordering costs a fraction of a
  // scalar one); the scalar matrix is then assembled already permuted and analyzed in natural order.
  std::vector<int> perm, pos(nb);
  // Incremental use (variables appended since the last build, none removed or re-fixed): keep the previous
  // elimination order and put the new blocks last, as a SLAM front end appends poses in time order. This
  // skips the ordering (AMD / METIS) of every rebuild; the symbolic analysis in the fixed order is redone
  // (cheap: elimination tree and counts). Guarded by the fill: if the factor grows more than
  // reuse_fill_tolerance beyond the last full ordering's fill per block, the graph is ordered afresh.
  bool prefix = reuse_ordering && !order_vars_.empty() && prev_ids_.size() <= nv;
  for (std::size_t v = 0; prefix && v < prev_ids_.size(); ++v) {
    prefix = vars[v].id == prev_ids_[v] && (block_of[v] >= 0) == (prev_active_[v] != 0);
  }
  ordering_reused_ = prefix;
  if (prefix) {
    perm.reserve(nb);
    for (std::size_t v : order_vars_) perm.push_back(block_of[v]);
    for (std::size_t v = prev_ids_.size(); v < nv; ++v) {
      if (block_of[v] >= 0) perm.push_back(block_of[v]);
    }
  } else if (ordering == 0) {
    // Auto: AMD, plus METIS nested dissection where the factorization will dominate the run. Estimated scalar
    // flops = block-graph flops x mean(d)^3; METIS costs roughly as much as a few AMD orderings per block, so it
    // is tried only above nd_min_flops_per_block and kept if it predicts >= 5 % fewer flops. Measured: 3D
    // tori/spheres -27..-34 % flops (torus3D 1.35e9 -> 9.8e8), city10000 -13 % but 0.17 s of METIS > the gain.
    double amd_flops = 0.0, mean_d = 0.0;
    perm = fillReducingOrdering(nb, ap, ai, 1, &amd_flops);
    for (int b = 0; b < nb; ++b) mean_d += tangentDim(vars[var_of_block[b]].kind);
    mean_d = nb > 0 ? mean_d / nb : 0.0;
    if (nb > 0 && amd_flops * mean_d * mean_d * mean_d > nd_min_flops_per_block * nb) {
      double nd_flops = 0.0;
      std::vector<int> nd = fillReducingOrdering(nb, ap, ai, 2, &nd_flops);
      if (nd_flops < 0.95 * amd_flops) perm.swap(nd);
    }
  } else {
    perm = fillReducingOrdering(nb, ap, ai, ordering);
  }
  for (int k = 0; k < nb; ++k) pos[perm[k]] = k;

  var_offset_.assign(nv, -1);
  std::vector<int> block_off(nb), block_dim(nb);
  int n = 0;
  for (int k = 0; k < nb; ++k) {
    const int b = perm[k];
    block_dim[b] = tangentDim(vars[var_of_block[b]].kind);
    block_off[b] = n;
    var_offset_[var_of_block[b]] = n;
    n += block_dim[b];
  }
  n_ = n;

  // Per block column: the row blocks above the diagonal, in position order, and their relative offsets.
  std::vector<std::vector<std::pair<int, int>>> col_rows(nb);  // (pos of row block, rel offset)
  std::vector<int> diag_rel(nb);
  for (int b = 0; b < nb; ++b) {
    auto& rows = col_rows[b];
    for (int r : adj[b]) {
      if (pos[r] < pos[b]) rows.emplace_back(pos[r], 0);
    }
    std::sort(rows.begin(), rows.end());
    int rel = 0;
    for (auto& [p, off] : rows) {
      off = rel;
      rel += block_dim[perm[p]];
    }
    diag_rel[b] = rel;
  }

  std::vector<int> col_ptr(n + 1, 0), row_idx;
  diag_index_.assign(n, 0);
  for (int k = 0; k < nb; ++k) {
    const int b = perm[k];
    for (int c = 0; c < block_dim[b]; ++c) {
      const int col = block_off[b] + c;
      col_ptr[col + 1] = col_ptr[col] + diag_rel[b] + c + 1;
    }
  }
  row_idx.resize(col_ptr[n]);
  for (int k = 0; k < nb; ++k) {
    const int b = perm[k];
    for (int c = 0; c < block_dim[b]; ++c) {
      const int col = block_off[b] + c;
      int w = col_ptr[col];
      for (const auto& [p, rel] : col_rows[b]) {
        const int r = perm[p];
        for (int q = 0; q < block_dim[r]; ++q) row_idx[w++] = block_off[r] + q;
      }
      for (int q = 0; q <= c; ++q) row_idx[w++] = block_off[b] + q;
      diag_index_[col] = w - 1;
    }
  }

  auto find_rel = [&](int col_block, int row_block) {
    const auto& rows = col_rows[col_block];
    const auto it = std::lower_bound(rows.begin(), rows.end(), std::make_pair(pos[row_block], -1));
    return it->second;
  };
  slots_.assign(factors.size(), FactorSlots{});
  for (std::size_t fi = 0; fi < factors.size(); ++fi) {
    const Factor& f = factors[fi];
    FactorSlots& s = slots_[fi];
    if (f.kind == FactorKind::kBetween2) {
      s.cz = std::cos(f.z2.theta);
      s.sz = std::sin(f.z2.theta);
    }
    const int na = arity(f.kind);
    int blk[2] = {-1, -1};
    for (int a = 0; a < na; ++a) {
      blk[a] = block_of[f.var[a]];
      if (blk[a] >= 0) {
        s.off[a] = block_off[blk[a]];
        s.diag_rel[a] = diag_rel[blk[a]];
      }
    }
    if (na == 2 && blk[0] >= 0 && blk[1] >= 0) {
      if (pos[blk[0]] < pos[blk[1]]) {
        s.first_is_row = true;
        s.pair_rel = find_rel(blk[1], blk[0]);
      } else {
        s.first_is_row = false;
        s.pair_rel = find_rel(blk[0], blk[1]);
      }
    }
  }

  chol_.setPattern(n, col_ptr, row_idx);
  if (n > 0) chol_.analyze(/*natural_ordering=*/true, factorization);

  const double fill_per_block = nb > 0 ? chol_.factorNonzeros() / nb : 0.0;
  if (ordering_reused_ && fill_per_block > (1.0 + reuse_fill_tolerance) * full_fill_per_block_) {
    build(graph, gauge, ordering, factorization, nd_min_flops_per_block, /*reuse_ordering=*/false,
          reuse_fill_tolerance);
    return;
  }
  if (!ordering_reused_) full_fill_per_block_ = fill_per_block;
  prev_ids_.resize(nv);
  prev_active_.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    prev_ids_[v] = vars[v].id;
    prev_active_[v] = block_of[v] >= 0 ? 1 : 0;
  }
  order_vars_.resize(nb);
  for (int k = 0; k < nb; ++k) order_vars_[k] = var_of_block[perm[k]];
}

namespace {

template <int R, int A, int B>
struct Linearized {
  Eigen::Matrix<double, R, 1> e;
  Eigen::Matrix<double, R, A> ja;
  Eigen::Matrix<double, R, B> jb;
};

// Adds w * J^T Omega J and w * J^T Omega e of one factor into the upper-stored Hessian values hx and g.
template <int R, int A, int B>
void accumulate(const FactorSlots& s, const Linearized<R, A, B>& lin, const Eigen::Matrix<double, R, R>& w_omega,
                const int* colp, double* hx, double* g) {
  const Eigen::Matrix<double, R, 1> we = w_omega * lin.e;
  const Eigen::Matrix<double, A, R> ja_w = lin.ja.transpose() * w_omega;
  if (s.off[0] >= 0) {
    const Eigen::Matrix<double, A, A> haa = ja_w * lin.ja;
    for (int k = 0; k < A; ++k) {
      double* colv = hx + colp[s.off[0] + k] + s.diag_rel[0];
      for (int r = 0; r <= k; ++r) colv[r] += haa(r, k);
    }
    Eigen::Map<Eigen::Matrix<double, A, 1>>(g + s.off[0]) += lin.ja.transpose() * we;
  }
  if constexpr (B > 0) {
    if (s.off[1] >= 0) {
      const Eigen::Matrix<double, B, R> jb_w = lin.jb.transpose() * w_omega;
      const Eigen::Matrix<double, B, B> hbb = jb_w * lin.jb;
      for (int k = 0; k < B; ++k) {
        double* colv = hx + colp[s.off[1] + k] + s.diag_rel[1];
        for (int r = 0; r <= k; ++r) colv[r] += hbb(r, k);
      }
      Eigen::Map<Eigen::Matrix<double, B, 1>>(g + s.off[1]) += lin.jb.transpose() * we;
      if (s.pair_rel >= 0) {
        const Eigen::Matrix<double, A, B> hab = ja_w * lin.jb;
        if (s.first_is_row) {
          for (int k = 0; k < B; ++k) {
            double* colv = hx + colp[s.off[1] + k] + s.pair_rel;
            for (int r = 0; r < A; ++r) colv[r] += hab(r, k);
          }
        } else {
          for (int k = 0; k < A; ++k) {
            double* colv = hx + colp[s.off[0] + k] + s.pair_rel;
            for (int r = 0; r < B; ++r) colv[r] += hab(k, r);
          }
        }
      }
    }
  }
}

template <int R, int A, int B>
double finish(const Factor& f, const FactorSlots& s, const Linearized<R, A, B>& lin, const int* colp, double* hx,
              double* g, double* chi2) {
  const Eigen::Matrix<double, R, R> omega = f.information.template topLeftCorner<R, R>();
  const double raw = lin.e.dot(omega * lin.e);
  *chi2 += raw;
  double rho = raw, drho = 1.0;
  f.kernel.evaluate(f.weight * raw, rho, drho);
  const double w = f.weight * drho;
  if (w > 0.0) accumulate<R, A, B>(s, lin, w * omega, colp, hx, g);
  return rho;
}

double linearizeFactor(const Factor& f, const FactorSlots& s, const std::vector<Variable>& x,
                       const Eigen::Vector2d* trig, const int* colp, double* hx, double* g, double* chi2) {
  const Variable& a = x[f.var[0]];
  switch (f.kind) {
    case FactorKind::kBetween2: {
      Linearized<3, 3, 3> l;
      Eigen::Matrix3d ja, jb;
      const Eigen::Vector2d& ti = trig[f.var[0]];
      l.e = errorBetween2(a.pose2, x[f.var[1]].pose2, f.z2, ti.x(), ti.y(), s.cz, s.sz, &ja, &jb);
      l.ja = ja;
      l.jb = jb;
      return finish(f, s, l, colp, hx, g, chi2);
    }
    case FactorKind::kBetween3: {
      Linearized<6, 6, 6> l;
      l.e = errorBetween3(a.pose3, x[f.var[1]].pose3, f.z3, &l.ja, &l.jb);
      return finish(f, s, l, colp, hx, g, chi2);
    }
    case FactorKind::kPrior2: {
      Linearized<3, 3, 0> l;
      Eigen::Matrix3d ja;
      l.e = errorPrior2(a.pose2, f.z2, &ja);
      l.ja = ja;
      return finish(f, s, l, colp, hx, g, chi2);
    }
    case FactorKind::kPrior3: {
      Linearized<6, 6, 0> l;
      l.e = errorPrior3(a.pose3, f.z3, &l.ja);
      return finish(f, s, l, colp, hx, g, chi2);
    }
    case FactorKind::kPose2Point2: {
      Linearized<2, 3, 2> l;
      Eigen::Matrix2d jb;
      l.e = errorPose2Point2(a.pose2, x[f.var[1]].point.head<2>(), f.zp.head<2>(), &l.ja, &jb);
      l.jb = jb;
      return finish(f, s, l, colp, hx, g, chi2);
    }
    case FactorKind::kPose3Point3: {
      Linearized<3, 6, 3> l;
      Eigen::Matrix3d jb;
      l.e = errorPose3Point3(a.pose3, x[f.var[1]].point, f.zp, &l.ja, &jb);
      l.jb = jb;
      return finish(f, s, l, colp, hx, g, chi2);
    }
  }
  return 0.0;
}

double evaluateFactor(const Factor& f, const FactorSlots& s, const std::vector<Variable>& x,
                      const Eigen::Vector2d* trig, double* chi2) {
  double raw = 0.0;
  // Fixed-size paths for the relative-pose factors (the bulk of every benchmark graph; trial steps, the step
  // extension and the dogleg look-ahead evaluate the cost often); the generic path for the rest.
  if (f.kind == FactorKind::kBetween2) {
    const Eigen::Vector2d& ti = trig[f.var[0]];
    const Eigen::Vector3d e =
        errorBetween2(x[f.var[0]].pose2, x[f.var[1]].pose2, f.z2, ti.x(), ti.y(), s.cz, s.sz, nullptr, nullptr);
    raw = e.dot(f.information.topLeftCorner<3, 3>() * e);
  } else if (f.kind == FactorKind::kBetween3) {
    const Vector6d e = errorBetween3(x[f.var[0]].pose3, x[f.var[1]].pose3, f.z3, nullptr, nullptr);
    raw = e.dot(f.information * e);
  } else {
    const int d = errorDim(f.kind);
    const Vector6d e = factorError(f, x);
    raw = e.head(d).dot(f.information.topLeftCorner(d, d) * e.head(d));
  }
  *chi2 += raw;
  double rho = raw, drho = 1.0;
  f.kernel.evaluate(f.weight * raw, rho, drho);
  return rho;
}

// Runs body(thread, begin, end) over [0, count) split into `threads` contiguous ranges.
template <typename Body>
void parallelRanges(std::size_t count, int threads, Body&& body) {
  // A thread start costs ~20-50 us: below ~4000 factors per thread one thread is faster (MIT: 827 factors).
  threads = std::max(1, std::min<int>(threads, static_cast<int>(count / 4096) + 1));
  if (threads == 1) {
    body(0, std::size_t{0}, count);
    return;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (count + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    const std::size_t b = std::min(count, t * chunk), e = std::min(count, (t + 1) * chunk);
    pool.emplace_back([&body, t, b, e] { body(t, b, e); });
  }
  body(0, std::size_t{0}, std::min(count, chunk));
  for (auto& th : pool) th.join();
}

}  // namespace

void computeHeadingTrig(const std::vector<Variable>& values, HeadingTrig& out) {
  out.resize(values.size());
  for (std::size_t v = 0; v < values.size(); ++v) {
    const double th = values[v].pose2.theta;
    out[v] = values[v].kind == VariableKind::kPose2 ? Eigen::Vector2d(std::cos(th), std::sin(th))
                                                     : Eigen::Vector2d::Zero();
  }
}

double BlockSystem::linearize(const PoseGraph& graph, const std::vector<Variable>& values, Eigen::VectorXd& grad,
                              int threads, double* chi2, const HeadingTrig* trig) {
  if (trig == nullptr) {
    computeHeadingTrig(values, trig_scratch_);
    trig = &trig_scratch_;
  }
  const Eigen::Vector2d* tr = trig->data();
  const auto& factors = graph.factors();
  const int nnz = n_ > 0 ? chol_.colPtr()[n_] : 0;
  const int* colp = n_ > 0 ? chol_.colPtr() : nullptr;
  double* h0 = n_ > 0 ? chol_.values() : nullptr;
  grad.setZero(n_);
  if (h0 != nullptr) std::fill_n(h0, nnz, 0.0);
  const int nt = std::max(1, threads);
  if (static_cast<int>(thread_h_.size()) < nt) {
    thread_h_.resize(nt);
    thread_g_.resize(nt);
  }
  std::vector<double> cost(nt, 0.0), c2(nt, 0.0);
  std::vector<char> used(nt, 0);
  parallelRanges(factors.size(), nt, [&](int t, std::size_t b, std::size_t e) {
    double* hx = h0;
    double* g = grad.data();
    if (t > 0) {
      thread_h_[t].assign(nnz, 0.0);
      thread_g_[t].setZero(n_);
      hx = thread_h_[t].data();
      g = thread_g_[t].data();
    }
    used[t] = 1;
    double cc = 0.0, chi = 0.0;
    for (std::size_t fi = b; fi < e; ++fi) {
      cc += linearizeFactor(factors[fi], slots_[fi], values, tr, colp, hx, g, &chi);
    }
    cost[t] = cc;
    c2[t] = chi;
  });
  double total = cost[0], total_chi2 = c2[0];
  for (int t = 1; t < nt; ++t) {
    if (!used[t]) continue;
    for (int k = 0; k < nnz; ++k) h0[k] += thread_h_[t][k];
    grad += thread_g_[t];
    total += cost[t];
    total_chi2 += c2[t];
  }
  if (chi2 != nullptr) *chi2 = total_chi2;
  return total;
}

double BlockSystem::evaluate(const PoseGraph& graph, const std::vector<Variable>& values, int threads,
                             double* chi2, HeadingTrig& trig) const {
  computeHeadingTrig(values, trig);
  const Eigen::Vector2d* tr = trig.data();
  const auto& factors = graph.factors();
  const int nt = std::max(1, threads);
  std::vector<double> cost(nt, 0.0), c2(nt, 0.0);
  parallelRanges(factors.size(), nt, [&](int t, std::size_t b, std::size_t e) {
    double cc = 0.0, chi = 0.0;
    for (std::size_t fi = b; fi < e; ++fi) cc += evaluateFactor(factors[fi], slots_[fi], values, tr, &chi);
    cost[t] = cc;
    c2[t] = chi;
  });
  double total = 0.0, total_chi2 = 0.0;
  for (int t = 0; t < nt; ++t) {
    total += cost[t];
    total_chi2 += c2[t];
  }
  if (chi2 != nullptr) *chi2 = total_chi2;
  return total;
}

void BlockSystem::retract(const std::vector<Variable>& values, const Eigen::VectorXd& step,
                          std::vector<Variable>& out) const {
  // Only free variables are written; a full copy only when out is not already a same-sized state of this
  // system (the optimizer's trial buffers are copies of one state, so their fixed variables are identical).
  if (out.size() != values.size()) out = values;
  for (std::size_t v = 0; v < values.size(); ++v) {
    const int o = var_offset_[v];
    if (o < 0) continue;
    Variable& x = out[v];
    switch (x.kind) {
      case VariableKind::kPose2: x.pose2 = graph_slam::retract(values[v].pose2, Eigen::Vector3d(step.segment<3>(o))); break;
      case VariableKind::kPose3: x.pose3 = graph_slam::retract(values[v].pose3, Vector6d(step.segment<6>(o))); break;
      case VariableKind::kPoint2: x.point.head<2>() += step.segment<2>(o); break;
      case VariableKind::kPoint3: x.point += step.segment<3>(o); break;
    }
  }
}

}  // namespace cairn::graph_slam::detail
