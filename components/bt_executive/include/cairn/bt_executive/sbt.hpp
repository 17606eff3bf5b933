// Stochastic behavior trees (Stüde §5.2.2, after Colledanchise, Marzinotto and Ögren 2014 [CMÖ14]).
//
// A tree of Sequence/Fallback nodes over actions A = <p_s, mu, nu> and conditions C = <p_s>. An action succeeds
// with probability p_s after an Exp(mu) time, else fails after an Exp(nu) time; a condition answers at once.
// The single-pass execution of the tree is a continuous-time Markov chain: every action has two running phases
// ("will succeed" leaving at rate mu, "will fail" leaving at rate nu) entered with p_s and 1-p_s, and two
// absorbing states S and F. pi(t) solves pi' = Q pi (eq. 5.2) and p_s,T(t) = pi_S(t), p_f,T(t) = pi_F(t)
// (eq. 5.1), computed with the matrix exponential. The tree rates are mu_T = 1/E[T | S] and nu_T = 1/E[T | F]
// from the fundamental matrix of the chain (exact; the thesis' eqs. 5.3/5.4 approximate the same quantities
// through the matrices H and U of [CMÖ14], which it does not spell out).
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

namespace cairn::bt::sbt {

struct Node {
  enum class Kind { Sequence, Fallback, Action, Condition };
  Kind kind = Kind::Action;
  std::string name;
  double p_success = 1.0;  ///< p_s: probability to (eventually) succeed
  double mu = 1.0;         ///< success rate [1/s] (actions)
  double nu = 1.0;         ///< failure rate [1/s] (actions)
  std::vector<Node> children;
};

Node action(std::string name, double p_success, double mu, double nu);
Node condition(std::string name, double p_success);
Node sequence(std::vector<Node> children, std::string name = "Sequence");
Node fallback(std::vector<Node> children, std::string name = "Fallback");

class Analysis {
 public:
  /// Builds the chain; throws std::invalid_argument for probabilities outside [0,1], non-positive rates of
  /// reachable outcomes, or empty control nodes.
  explicit Analysis(const Node& root);

  /// {p_s,T(t), p_f,T(t)} (eq. 5.1) by exp(Q t) pi0.
  std::pair<double, double> probabilities(double t) const;
  double successProbability(double t) const { return probabilities(t).first; }
  /// Probabilities at many times (one exponential per step of a uniform grid when times are equally spaced).
  std::vector<std::pair<double, double>> probabilities(const std::vector<double>& times) const;

  double successProbability() const { return p_success_; }  ///< t -> infinity
  double failureProbability() const { return p_failure_; }
  double successRate() const { return mu_T_; }  ///< mu_T = 1 / E[T | success]
  double failureRate() const { return nu_T_; }  ///< nu_T = 1 / E[T | failure]

  const Eigen::MatrixXd& generator() const { return Q_; }
  const Eigen::VectorXd& initial() const { return pi0_; }
  const std::vector<std::string>& stateNames() const { return names_; }
  int successState() const { return s_; }
  int failureState() const { return f_; }

 private:
  Eigen::MatrixXd Q_;
  Eigen::VectorXd pi0_;
  std::vector<std::string> names_;
  int s_ = 0, f_ = 0;
  double p_success_ = 0, p_failure_ = 0, mu_T_ = 0, nu_T_ = 0;
};

/// Monte-Carlo execution of the same tree with sampled outcomes and durations: {p_s(t), p_f(t)} at `times`.
std::vector<std::pair<double, double>> monteCarlo(const Node& root, const std::vector<double>& times,
                                                  std::size_t samples, std::uint64_t seed);

/// The same tree as BehaviorTree.CPP v4 XML (actions/conditions as <Action ID=name/>), for display and for
/// running the synthesized trees with the engine.
std::string toXml(const Node& root, const std::string& tree_id = "SBT");

}  // namespace cairn::bt::sbt
