#include "cairn/bt_executive/sbt.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

namespace cairn::bt::sbt {

Node action(std::string name, double p_success, double mu, double nu) {
  Node n;
  n.kind = Node::Kind::Action;
  n.name = std::move(name);
  n.p_success = p_success;
  n.mu = mu;
  n.nu = nu;
  return n;
}
Node condition(std::string name, double p_success) {
  Node n;
  n.kind = Node::Kind::Condition;
  n.name = std::move(name);
  n.p_success = p_success;
  return n;
}
Node sequence(std::vector<Node> children, std::string name) {
  Node n;
  n.kind = Node::Kind::Sequence;
  n.name = std::move(name);
  n.children = std::move(children);
  return n;
}
Node fallback(std::vector<Node> children, std::string name) {
  Node n;
  n.kind = Node::Kind::Fallback;
  n.name = std::move(name);
  n.children = std::move(children);
  return n;
}

namespace {

struct Flat {
  const Node* node;
  int parent;
  int index_in_parent;
  std::vector<int> children;
  int action_id = -1;
};

using Dist = std::map<int, double>;  // state -> probability

class ChainBuilder {
 public:
  explicit ChainBuilder(const Node& root) {
    flatten(root, -1, 0);
    n_actions_ = 0;
    for (auto& f : flat_)
      if (f.node->kind == Node::Kind::Action) f.action_id = n_actions_++;
    s_ = 2 * n_actions_;
    f_ = s_ + 1;
  }
  int states() const { return 2 * n_actions_ + 2; }
  int successState() const { return s_; }
  int failureState() const { return f_; }

  void build(Eigen::MatrixXd& Q, Eigen::VectorXd& pi0, std::vector<std::string>& names) {
    const int n = states();
    Q = Eigen::MatrixXd::Zero(n, n);
    pi0 = Eigen::VectorXd::Zero(n);
    names.assign(static_cast<std::size_t>(n), "");
    names[static_cast<std::size_t>(s_)] = "SUCCESS";
    names[static_cast<std::size_t>(f_)] = "FAILURE";
    Dist d0;
    start(0, 1.0, d0);
    for (auto [s, p] : d0) pi0(s) += p;
    for (std::size_t i = 0; i < flat_.size(); ++i) {
      const auto& fl = flat_[i];
      if (fl.action_id < 0) continue;
      const Node& a = *fl.node;
      const int rs = 2 * fl.action_id, rf = rs + 1;
      names[static_cast<std::size_t>(rs)] = a.name + ".running->S";
      names[static_cast<std::size_t>(rf)] = a.name + ".running->F";
      // Unreachable phases get a unit exit rate so that the transient block stays invertible.
      const double mu = a.p_success > 0 ? a.mu : 1.0;
      const double nu = a.p_success < 1 ? a.nu : 1.0;
      Dist ds, df;
      finish(static_cast<int>(i), true, 1.0, ds);
      finish(static_cast<int>(i), false, 1.0, df);
      Q(rs, rs) -= mu;
      for (auto [s, p] : ds) Q(s, rs) += mu * p;
      Q(rf, rf) -= nu;
      for (auto [s, p] : df) Q(s, rf) += nu * p;
    }
  }

 private:
  void flatten(const Node& n, int parent, int idx) {
    const int me = static_cast<int>(flat_.size());
    flat_.push_back({&n, parent, idx, {}, -1});
    if (n.kind == Node::Kind::Sequence || n.kind == Node::Kind::Fallback) {
      if (n.children.empty()) throw std::invalid_argument("SBT control node '" + n.name + "' has no children");
    } else {
      if (!(n.p_success >= 0.0 && n.p_success <= 1.0))
        throw std::invalid_argument("SBT node '" + n.name + "': p_s must be in [0,1]");
      if (n.kind == Node::Kind::Action) {
        if (n.p_success > 0 && !(n.mu > 0)) throw std::invalid_argument("SBT action '" + n.name + "': mu must be > 0");
        if (n.p_success < 1 && !(n.nu > 0)) throw std::invalid_argument("SBT action '" + n.name + "': nu must be > 0");
      }
    }
    for (std::size_t k = 0; k < n.children.size(); ++k) {
      flat_[static_cast<std::size_t>(me)].children.push_back(static_cast<int>(flat_.size()));
      flatten(n.children[k], me, static_cast<int>(k));
    }
  }

  /// Distribution of the next state when node `i` is started (with weight w).
  void start(int i, double w, Dist& out) {
    if (w == 0.0) return;
    const auto& fl = flat_[static_cast<std::size_t>(i)];
    switch (fl.node->kind) {
      case Node::Kind::Action:
        out[2 * fl.action_id] += w * fl.node->p_success;
        out[2 * fl.action_id + 1] += w * (1.0 - fl.node->p_success);
        return;
      case Node::Kind::Condition:
        finish(i, true, w * fl.node->p_success, out);
        finish(i, false, w * (1.0 - fl.node->p_success), out);
        return;
      default: start(fl.children.front(), w, out);
    }
  }

  /// Distribution of the next state when node `i` has completed with `success` (Stüde Alg. 5.1/5.2 flow).
  void finish(int i, bool success, double w, Dist& out) {
    if (w == 0.0) return;
    const auto& fl = flat_[static_cast<std::size_t>(i)];
    if (fl.parent < 0) {
      out[success ? s_ : f_] += w;
      return;
    }
    const auto& par = flat_[static_cast<std::size_t>(fl.parent)];
    const bool continue_on = par.node->kind == Node::Kind::Sequence ? success : !success;
    const std::size_t next = static_cast<std::size_t>(fl.index_in_parent) + 1;
    if (continue_on && next < par.children.size()) start(par.children[next], w, out);
    else finish(fl.parent, success, w, out);
  }

  std::vector<Flat> flat_;
  int n_actions_ = 0, s_ = 0, f_ = 0;
};

}  // namespace

Analysis::Analysis(const Node& root) {
  ChainBuilder b(root);
  b.build(Q_, pi0_, names_);
  s_ = b.successState();
  f_ = b.failureState();
  const int nt = b.states() - 2;  // transient states come first
  const double s0 = pi0_(s_), f0 = pi0_(f_);
  if (nt == 0) {
    p_success_ = s0;
    p_failure_ = f0;
    return;
  }
  const Eigen::MatrixXd QT = Q_.topLeftCorner(nt, nt);
  const Eigen::RowVectorXd rS = Q_.block(s_, 0, 1, nt), rF = Q_.block(f_, 0, 1, nt);
  const Eigen::VectorXd p0 = pi0_.head(nt);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu(QT);
  const Eigen::VectorXd x1 = lu.solve(p0);   // Q^-1 pi0
  const Eigen::VectorXd x2 = lu.solve(x1);   // Q^-2 pi0
  p_success_ = s0 - rS.dot(x1);
  p_failure_ = f0 - rF.dot(x1);
  const double ts = rS.dot(x2), tf = rF.dot(x2);  // E[T 1_S], E[T 1_F]
  mu_T_ = ts > 0 ? p_success_ / ts : 0.0;
  nu_T_ = tf > 0 ? p_failure_ / tf : 0.0;
}

std::pair<double, double> Analysis::probabilities(double t) const {
  const Eigen::MatrixXd E = (Q_ * t).exp();
  const Eigen::VectorXd pi = E * pi0_;
  return {pi(s_), pi(f_)};
}

std::vector<std::pair<double, double>> Analysis::probabilities(const std::vector<double>& times) const {
  std::vector<std::pair<double, double>> out;
  out.reserve(times.size());
  bool uniform = times.size() > 2 && times.front() == 0.0;
  const double dt = times.size() > 1 ? times[1] - times[0] : 0.0;
  for (std::size_t k = 1; uniform && k < times.size(); ++k)
    uniform = std::abs((times[k] - times[k - 1]) - dt) <= 1e-9 * std::max(1.0, dt);
  if (!uniform) {
    for (double t : times) out.push_back(probabilities(t));
    return out;
  }
  const Eigen::MatrixXd step = (Q_ * dt).exp();
  Eigen::VectorXd pi = pi0_;
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (k > 0) pi = step * pi;
    out.push_back({pi(s_), pi(f_)});
  }
  return out;
}

std::vector<std::pair<double, double>> monteCarlo(const Node& root, const std::vector<double>& times,
                                                  std::size_t samples, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // returns success; accumulates time
  std::function<bool(const Node&, double&)> run = [&](const Node& n, double& t) -> bool {
    switch (n.kind) {
      case Node::Kind::Condition: return U(rng) < n.p_success;
      case Node::Kind::Action: {
        const bool ok = U(rng) < n.p_success;
        t += std::exponential_distribution<double>(ok ? n.mu : n.nu)(rng);
        return ok;
      }
      case Node::Kind::Sequence:
        for (const auto& c : n.children)
          if (!run(c, t)) return false;
        return true;
      case Node::Kind::Fallback:
        for (const auto& c : n.children)
          if (run(c, t)) return true;
        return false;
    }
    return false;
  };
  std::vector<std::pair<double, double>> counts(times.size(), {0.0, 0.0});
  for (std::size_t i = 0; i < samples; ++i) {
    double t = 0.0;
    const bool ok = run(root, t);
    for (std::size_t k = 0; k < times.size(); ++k)
      if (t <= times[k]) (ok ? counts[k].first : counts[k].second) += 1.0;
  }
  for (auto& c : counts) {
    c.first /= static_cast<double>(samples);
    c.second /= static_cast<double>(samples);
  }
  return counts;
}

namespace {
void xmlNode(const Node& n, std::ostringstream& os, int depth) {
  std::string ind(static_cast<std::size_t>(2 * depth), ' ');
  switch (n.kind) {
    case Node::Kind::Action: os << ind << "<Action ID=\"" << n.name << "\"/>\n"; return;
    case Node::Kind::Condition: os << ind << "<Condition ID=\"" << n.name << "\"/>\n"; return;
    default: {
      const char* tag = n.kind == Node::Kind::Sequence ? "Sequence" : "Fallback";
      os << ind << "<" << tag << ">\n";
      for (const auto& c : n.children) xmlNode(c, os, depth + 1);
      os << ind << "</" << tag << ">\n";
    }
  }
}
}  // namespace

std::string toXml(const Node& root, const std::string& tree_id) {
  std::ostringstream os;
  os << "<root BTCPP_format=\"4\">\n  <BehaviorTree ID=\"" << tree_id << "\">\n";
  xmlNode(root, os, 2);
  os << "  </BehaviorTree>\n</root>\n";
  return os.str();
}

}  // namespace cairn::bt::sbt
