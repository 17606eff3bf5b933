// Person-search behavior trees (Stüde §5.4, [SLPS21]): wait and search actions from a people-activity model,
// place sampling with deduplication, open-TSP ordering, enumeration and stochastic analysis of candidate trees,
// baselines GM, GC, RND, W and PP (§5.4.4).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "cairn/bt_executive/sbt.hpp"

namespace cairn::bt::psbt {

/// Piece-wise constant rate λ(x, t) on a grid for one time interval (eq. 5.7): rate(i, j) is the arrival rate
/// density in people / (s m²) of cell (i = x index, j = y index).
struct GridModel {
  double resolution = 1.0;  ///< cell size [m]
  Eigen::MatrixXd rate;     ///< rows: x cells, cols: y cells
  int width() const { return static_cast<int>(rate.rows()); }
  int height() const { return static_cast<int>(rate.cols()); }
  Eigen::Vector2d cellCenter(int i, int j) const { return {(i + 0.5) * resolution, (j + 0.5) * resolution}; }
  /// ∫_D λ over the disc of radius r around c (cell centres inside the disc; eq. 5.9 / 5.14).
  double integrateDisc(const Eigen::Vector2d& c, double r) const;
};

/// Synthetic office floor: base rate plus Gaussian hotspots (for psbt-eval; the thesis' model is not public).
GridModel syntheticHotspots(double width_m, double height_m, double resolution, int hotspots, std::uint64_t seed);

/// Parameters of §5.4.4.
struct Params {
  double r_D = 2.0;         ///< detection radius [m]
  double p_conf = 0.9;      ///< confidence p'_s
  double dt = 1.0;          ///< path discretization Δt [s]
  double l_fail = 100.0;    ///< expected distance between navigation failures [m]
  double v = 0.5;           ///< mean velocity v̄_sp [m/s]
  int n_pl = 6;             ///< sampled places
  double t_max = 200.0;     ///< look-ahead time [s]
  double max_distance = 30.0;  ///< places farther from the help location are not sampled [m]
  int sample_attempts = 2000;
};

/// SBT parameters of one action.
struct ActionStats {
  double p_s = 0, mu = 0, nu = 0;
  double length = 0;  ///< path length (search / move)
};

/// Wait at x (eqs. 5.9-5.12): mu_w = ∫_D λ, T' = -log(1 - p'_s)/mu_w, nu_w = 1/T', p_s = p'_s.
ActionStats waitAction(const GridModel& m, const Eigen::Vector2d& x, const Params& p);
/// Search on the straight path a -> b (eqs. 5.14-5.18).
ActionStats searchAction(const GridModel& m, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Params& p);
/// Move back to the help location: fails only through navigation (rate v/l_fail), succeeds after l/v.
ActionStats moveAction(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Params& p);
/// The same for a path of `length` metres.
ActionStats moveAction(double length, const Params& p);

/// Places sampled with probability ∝ ∫_cell λ within max_distance, deduplicated within r_D (keeping the larger
/// rate), at most n_pl (§5.4.3).
std::vector<Eigen::Vector2d> samplePlaces(const GridModel& m, const Eigen::Vector2d& start, const Params& p,
                                          std::mt19937_64& rng, bool uniform = false);

/// Open TSP from node 0 over a cost matrix: exact (Held-Karp) up to 12 nodes, genetic algorithm above.
std::vector<int> openTsp(const Eigen::MatrixXd& cost, std::uint64_t seed = 1);
double tourCost(const Eigen::MatrixXd& cost, const std::vector<int>& order);

/// A candidate tree: for each place in tour order 0 = skip, 1 = search to it, 2 = search to it and wait;
/// wait_at_start adds a wait at the help location before the tour.
struct Plan {
  bool wait_at_start = false;
  std::vector<int> choice;
  std::vector<Eigen::Vector2d> places;  ///< in tour order (excluding the help location)
  sbt::Node tree;
  double p_success_tmax = 0;  ///< p_s,T(t_max)
  double mu_T = 0;            ///< tree success rate (1/E[T | S])
};

/// Builds Sequence(Fallback(actions...), MoveBack) for a plan (Stüde Fig. 5.9 form).
sbt::Node buildTree(const GridModel& m, const Eigen::Vector2d& start, const std::vector<Eigen::Vector2d>& places,
                    bool wait_at_start, const std::vector<int>& choice, const Params& p);

struct Synthesis {
  Plan best;
  std::size_t candidates = 0;
  std::vector<Eigen::Vector2d> sampled;  ///< before ordering
};

/// PSBT: sample places, order them by open TSP on expected times to fail, enumerate the 2·3^{n} candidate trees
/// (contains the thesis' 3^{n_pl}+1), pick the one with maximal p_s,T(t_max).
Synthesis synthesize(const GridModel& m, const Eigen::Vector2d& start, const Params& p, std::mt19937_64& rng);

enum class Baseline { GM, GC, RND, W, PP };
const char* toString(Baseline b);
/// Baseline trees of §5.4.4 (GC uses the n_lambda = 50 highest cells).
Plan baseline(Baseline b, const GridModel& m, const Eigen::Vector2d& start, const Params& p, std::mt19937_64& rng,
              int n_lambda = 50);

/// The plan as BehaviorTree.CPP v4 XML with WaitForPerson / SearchPerson / MoveTo actions (x, y ports; the wait
/// timeout is T' of eq. 5.11).
std::string toXml(const GridModel& m, const Eigen::Vector2d& start, const Plan& plan, const Params& p);

}  // namespace cairn::bt::psbt
