// Correlative scan matching on a probability grid.
//  * correlativeMatch(): real-time correlative scan matching (Olson 2009, "Real-Time Correlative Scan
//    Matching"; Cartographer's RealTimeCorrelativeScanMatcher2D): exhaustive search over a window at grid
//    resolution in translation and at the angular step that moves the farthest point by at most one cell.
//  * BranchAndBoundMatcher: the same search space, searched with branch and bound over precomputed
//    max-pooled grids (Hess et al. 2016 §V-C, Algorithm 3): exact (same optimum as exhaustive search),
//    fast on large windows; matchFull() searches the whole grid and all angles (global localization).
// Score of a pose: mean matching value (ProbabilityGrid::matchValue, unknown = p_min) of the points, in [0, 1].
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/probability_grid.hpp"

namespace cairn::graph_slam {

struct SearchWindow {
  double linear = 0.15;   ///< +- metres in x and y
  double angular = 0.35;  ///< +- radians
  /// correlativeMatch() only: candidates are ranked by score * exp(-(wt |dt| + wr |dθ|)²) (Cartographer's
  /// translation/rotation_delta_cost_weight); 0 = plain score. The returned score is never penalized.
  double translation_weight = 0.0;  ///< 1/m
  double rotation_weight = 0.0;     ///< 1/rad
  /// Cap on the point range used for the angular step (0 = the farthest point): a few far points would
  /// otherwise force tiny steps.
  double max_step_range = 0.0;
};

struct MatchResult {
  Pose2 pose;        ///< pose of the points' frame in the grid frame
  double score = 0;  ///< mean matching value of the points at pose, in [0, 1]
};

/// Angular search step for points reaching out to `range` on a grid of `resolution` (Cartographer's
/// formula: the farthest point moves by at most one cell).
double angularSearchStep(double range, double resolution);

/// Real-time CSM around `initial` (pose of the points' frame in the grid frame). nullopt if no candidate
/// reaches min_score or there are no points.
std::optional<MatchResult> correlativeMatch(const ProbabilityGrid& g, const std::vector<Eigen::Vector2d>& pts,
                                            const Pose2& initial, const SearchWindow& w, double min_score);

/// Branch-and-bound matcher over one grid. Precomputation copies the grid (depth levels of max-pooled
/// values, levels >= 1 quantized to 8 bits, rounded up so they stay upper bounds); later changes to the
/// grid are not seen. Leaves are scored with the exact float values, so the optimum equals correlativeMatch()
/// with zero penalty weights on the same window.
class BranchAndBoundMatcher {
 public:
  explicit BranchAndBoundMatcher(const ProbabilityGrid& g, int depth = 7);

  std::optional<MatchResult> match(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                                   const SearchWindow& w, double min_score) const;
  /// Whole grid (every translation that puts some point on the grid), all angles in (-pi, pi].
  std::optional<MatchResult> matchFull(const std::vector<Eigen::Vector2d>& pts, double min_score) const;

  int depth() const { return depth_; }
  /// Number of leaf and inner candidates scored by the last match (diagnostics / benchmarks).
  std::size_t lastScoredCandidates() const { return scored_; }

 private:
  struct Level {
    int pad = 0;  ///< the level stores x in [-pad, width), y in [-pad, height)
    int w = 0, h = 0;
    std::vector<std::uint8_t> v;
  };
  std::optional<MatchResult> search(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                                    double linear, double angular, bool clip_to_grid, double min_score,
                                    double max_step_range) const;
  double resolution_;
  Eigen::Vector2d origin_;
  int width_ = 0, height_ = 0;
  float min_value_ = 0.1F;
  std::vector<float> level0_;  ///< matching values, width x height
  std::vector<Level> levels_;  ///< levels_[h-1] = max over 2^h x 2^h windows, h = 1..depth-1
  int depth_;
  mutable std::size_t scored_ = 0;
};

}  // namespace cairn::graph_slam
