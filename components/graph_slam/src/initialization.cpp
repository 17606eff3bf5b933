#include "cairn/graph_slam/initialization.hpp"

#include <cmath>
#include <deque>
#include <optional>
#include <stdexcept>

#include <Eigen/SVD>

#include "sparse_cholesky.hpp"

namespace cairn::graph_slam {

Initialization parseInitialization(const std::string& name) {
  if (name == "guess") return Initialization::kGuess;
  if (name == "odometry") return Initialization::kOdometry;
  if (name == "chordal") return Initialization::kChordal;
  throw std::invalid_argument("unknown initialization '" + name + "' (expected guess, odometry or chordal)");
}

namespace {

bool isPose(VariableKind k) { return k == VariableKind::kPose2 || k == VariableKind::kPose3; }
bool isBetween(FactorKind k) { return k == FactorKind::kBetween2 || k == FactorKind::kBetween3; }

std::optional<std::size_t> anchorOf(const PoseGraph& graph) {
  const auto& vars = graph.variables();
  for (std::size_t k = 0; k < vars.size(); ++k) {
    if (vars[k].fixed && isPose(vars[k].kind)) return k;
  }
  for (std::size_t k = 0; k < vars.size(); ++k) {
    if (isPose(vars[k].kind)) return k;
  }
  return std::nullopt;
}

// Places every point at its first observation from a pose.
void placePoints(std::vector<Variable>& x, const PoseGraph& graph) {
  std::vector<char> done(x.size(), 0);
  for (const Factor& f : graph.factors()) {
    const std::size_t p = f.var[1];
    if (done[p] || x[p].fixed) continue;
    if (f.kind == FactorKind::kPose2Point2) {
      const Pose2& pose = x[f.var[0]].pose2;
      x[p].point.head<2>() = pose.t + rotation2(pose.theta) * f.zp.head<2>();
      done[p] = 1;
    } else if (f.kind == FactorKind::kPose3Point3) {
      const Pose3& pose = x[f.var[0]].pose3;
      x[p].point = pose.t + pose.q * f.zp;
      done[p] = 1;
    }
  }
}

// Breadth-first order of the poses reachable from the anchor over relative-pose factors: (var, parent factor).
std::vector<std::pair<std::size_t, std::size_t>> spanningTree(const PoseGraph& graph, std::size_t anchor) {
  const auto& factors = graph.factors();
  std::vector<std::vector<std::size_t>> adj(graph.variables().size());
  for (std::size_t fi = 0; fi < factors.size(); ++fi) {
    if (!isBetween(factors[fi].kind)) continue;
    adj[factors[fi].var[0]].push_back(fi);
    adj[factors[fi].var[1]].push_back(fi);
  }
  std::vector<char> seen(adj.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> order;
  std::deque<std::size_t> queue{anchor};
  seen[anchor] = 1;
  while (!queue.empty()) {
    const std::size_t v = queue.front();
    queue.pop_front();
    for (std::size_t fi : adj[v]) {
      const Factor& f = factors[fi];
      const std::size_t w = f.var[0] == v ? f.var[1] : f.var[0];
      if (seen[w]) continue;
      seen[w] = 1;
      order.emplace_back(w, fi);
      queue.push_back(w);
    }
  }
  return order;
}

}  // namespace

void initializeOdometry(PoseGraph& graph) {
  const auto anchor = anchorOf(graph);
  if (!anchor) return;
  std::vector<Variable> x = graph.variables();
  const auto& factors = graph.factors();
  for (const auto& [w, fi] : spanningTree(graph, *anchor)) {
    const Factor& f = factors[fi];
    if (x[w].fixed) continue;
    const bool forward = f.var[1] == w;  // X_j = X_i * Z, else X_i = X_j * Z^-1
    const std::size_t from = forward ? f.var[0] : f.var[1];
    if (f.kind == FactorKind::kBetween2) {
      x[w].pose2 = compose(x[from].pose2, forward ? f.z2 : inverse(f.z2));
    } else {
      x[w].pose3 = compose(x[from].pose3, forward ? f.z3 : inverse(f.z3));
    }
  }
  placePoints(x, graph);
  graph.setValues(x);
}

void initializeChordal(PoseGraph& graph) {
  const auto anchor_opt = anchorOf(graph);
  if (!anchor_opt) return;
  const std::size_t anchor = *anchor_opt;
  const auto& vars = graph.variables();
  const auto& factors = graph.factors();
  const bool is3d = vars[anchor].kind == VariableKind::kPose3;
  const FactorKind between = is3d ? FactorKind::kBetween3 : FactorKind::kBetween2;
  for (const Factor& f : factors) {
    if (isBetween(f.kind) && f.kind != between) {
      throw std::invalid_argument("chordal initialization needs all relative-pose factors in one dimension");
    }
  }
  // Unknowns: the poses reachable from the anchor (anchor excluded).
  const auto tree = spanningTree(graph, anchor);
  std::vector<int> unknown(vars.size(), -1);
  int m = 0;
  for (const auto& [w, fi] : tree) unknown[w] = m++;
  if (m == 0) return;
  std::vector<Variable> x = graph.variables();
  const int d = is3d ? 3 : 2;  // block size of the rotation unknowns

  // Rotation relaxation. 2D: unknown r_i = (cos, sin) of R_i, r_j = Rot(theta_ij) r_i.
  // 3D: unknown rows of R_i (each row one right-hand side), row_j = R_ij^T row_i.
  // Residual per factor: x_j - A x_i, weighted by the mean rotational information (scalar, as in SE-Sync's kappa).
  std::vector<Eigen::Triplet<double>> h;
  const int nrhs = is3d ? 3 : 1;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m) * d, nrhs);
  auto anchor_rows = [&](std::size_t v) {
    Eigen::MatrixXd xv(d, nrhs);
    if (is3d) {
      xv = x[v].pose3.q.toRotationMatrix().transpose();  // column r = row r of R
    } else {
      xv(0, 0) = std::cos(x[v].pose2.theta);
      xv(1, 0) = std::sin(x[v].pose2.theta);
    }
    return xv;
  };
  auto add_block = [&](int bi, int bj, const Eigen::MatrixXd& blk) {  // H(bi, bj) += blk, upper only
    if (bi > bj) {
      const Eigen::MatrixXd t = blk.transpose();
      for (int r = 0; r < d; ++r)
        for (int c = 0; c < d; ++c) h.emplace_back(bj * d + r, bi * d + c, t(r, c));
      return;
    }
    for (int r = 0; r < d; ++r)
      for (int c = 0; c < d; ++c) {
        if (bi == bj && r > c) continue;
        h.emplace_back(bi * d + r, bj * d + c, blk(r, c));
      }
  };
  for (const Factor& f : factors) {
    if (f.kind != between) continue;
    const int ui = unknown[f.var[0]], uj = unknown[f.var[1]];
    const bool ki = f.var[0] == anchor, kj = f.var[1] == anchor;
    if ((ui < 0 && !ki) || (uj < 0 && !kj)) continue;  // not in the anchor's component
    Eigen::MatrixXd a(d, d);
    double w;
    if (is3d) {
      a = f.z3.q.toRotationMatrix().transpose();
      w = f.information.bottomRightCorner<3, 3>().trace() / 3.0;
    } else {
      a = rotation2(f.z2.theta);
      w = f.information(2, 2);
    }
    const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(d, d);
    if (!ki) add_block(ui, ui, w * a.transpose() * a);
    if (!kj) add_block(uj, uj, w * eye);
    if (!ki && !kj) add_block(ui, uj, -w * a.transpose());
    // Known anchor terms move to the right-hand side: J^T w (J_k x_k).
    if (ki && !kj) b.middleRows(uj * d, d) += w * a * anchor_rows(f.var[0]);
    if (kj && !ki) b.middleRows(ui * d, d) += w * a.transpose() * anchor_rows(f.var[1]);
  }
  const Eigen::MatrixXd rot = detail::solveSparseSpd(m * d, h, b);
  for (const auto& [v, fi] : tree) {
    (void)fi;
    const int u = unknown[v];
    if (x[v].fixed) continue;
    if (is3d) {
      const Eigen::Matrix3d r = rot.middleRows(u * 3, 3).transpose();
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
      s(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
      x[v].pose3.q = Eigen::Quaterniond(svd.matrixU() * s * svd.matrixV().transpose()).normalized();
    } else {
      x[v].pose2.theta = std::atan2(rot(u * 2 + 1, 0), rot(u * 2, 0));
    }
  }

  // Translations: t_j - t_i = R_i t_ij, a weighted graph Laplacian with one right-hand side per coordinate.
  const int dt = is3d ? 3 : 2;
  std::vector<Eigen::Triplet<double>> l;
  Eigen::MatrixXd bt = Eigen::MatrixXd::Zero(m, dt);
  for (const Factor& f : factors) {
    if (f.kind != between) continue;
    const int ui = unknown[f.var[0]], uj = unknown[f.var[1]];
    const bool ki = f.var[0] == anchor, kj = f.var[1] == anchor;
    if ((ui < 0 && !ki) || (uj < 0 && !kj)) continue;
    Eigen::VectorXd rt(dt);  // R_i t_ij
    double w;
    if (is3d) {
      rt = x[f.var[0]].pose3.q * f.z3.t;
      w = f.information.topLeftCorner<3, 3>().trace() / 3.0;
    } else {
      rt = rotation2(x[f.var[0]].pose2.theta) * f.z2.t;
      w = f.information.topLeftCorner<2, 2>().trace() / 2.0;
    }
    auto t_of = [&](std::size_t v) -> Eigen::VectorXd {
      if (is3d) return x[v].pose3.t;
      return x[v].pose2.t;
    };
    // residual r = t_j - t_i - rt; normal equations H t = -J^T w c.
    if (!ki) l.emplace_back(ui, ui, w);
    if (!kj) l.emplace_back(uj, uj, w);
    if (!ki && !kj) l.emplace_back(std::min(ui, uj), std::max(ui, uj), -w);
    if (!kj) bt.row(uj) += w * (rt + (ki ? t_of(f.var[0]) : Eigen::VectorXd::Zero(dt))).transpose();
    if (!ki) bt.row(ui) += w * ((kj ? t_of(f.var[1]) : Eigen::VectorXd::Zero(dt)) - rt).transpose();
  }
  const Eigen::MatrixXd trans = detail::solveSparseSpd(m, l, bt);
  for (const auto& [v, fi] : tree) {
    (void)fi;
    if (x[v].fixed) continue;
    if (is3d) {
      x[v].pose3.t = trans.row(unknown[v]).transpose();
    } else {
      x[v].pose2.t = trans.row(unknown[v]).transpose();
    }
  }
  placePoints(x, graph);
  graph.setValues(x);
}

void initialize(PoseGraph& graph, Initialization method) {
  switch (method) {
    case Initialization::kGuess: return;
    case Initialization::kOdometry: initializeOdometry(graph); return;
    case Initialization::kChordal: initializeChordal(graph); return;
  }
}

}  // namespace cairn::graph_slam
