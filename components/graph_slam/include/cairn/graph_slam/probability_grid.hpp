// Probability grid with hit/miss odds updates (Hess et al. 2016 §IV-B, Cartographer's submaps): every cell
// holds P(occupied) clamped to [p_min, p_max]; an insertion multiplies the odds of the cells with a return by
// odds(p_hit) and of the cells crossed by a ray by odds(p_miss), each cell at most once per insertion
// (hits win). The grid grows as needed. Submap = a grid plus its pose in the local SLAM frame.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/scan_filter.hpp"

namespace cairn::graph_slam {

struct ProbabilityGridOptions {
  double hit_probability = 0.55;   ///< Cartographer's default
  double miss_probability = 0.49;  ///< Cartographer's default
  double min_probability = 0.1;    ///< p_min: clamp; also the matching value of unknown cells
  double max_probability = 0.9;    ///< p_max
  bool insert_free_space = true;   ///< ray-cast misses along every beam
};

/// Integer cell index.
struct CellIndex {
  int x = 0;
  int y = 0;
};

class ProbabilityGrid {
 public:
  /// Probability of cells never observed, returned by probability() (export semantics: unknown).
  static constexpr double kUnknownProbability = 0.5;

  explicit ProbabilityGrid(double resolution = 0.05, ProbabilityGridOptions options = {});

  /// Inserts a scan taken with the base frame at `pose` in the grid frame: hits at the returns, misses along
  /// the rays from pose*data.origin to every return and every miss end. Grows the grid to fit.
  void insert(const RangeData& data, const Pose2& pose);

  /// P(occupied) of the cell containing p (grid frame); kUnknownProbability if unknown or outside.
  double probability(const Eigen::Vector2d& p) const;
  /// True if the cell containing p has been observed.
  bool known(const Eigen::Vector2d& p) const;
  /// Cell access (export): probability of cell (x, y) or kUnknownProbability; known flag.
  double probability(int x, int y) const;
  bool known(int x, int y) const;

  /// Matching value of a cell: P(occupied), p_min for unknown cells and cells outside the grid.
  float matchValue(int x, int y) const {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return static_cast<float>(options_.min_probability);
    return matchValueUnchecked(x, y);
  }
  float matchValueUnchecked(int x, int y) const {
    const float v = cells_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
    return v > min_value_ ? v : min_value_;
  }
  /// Bicubic (Catmull-Rom / Keys a = -0.5, as Ceres' BiCubicInterpolator) interpolation of the matching
  /// value at p (grid frame) over cell centres, with its gradient (per metre) if grad != nullptr.
  double interpolate(const Eigen::Vector2d& p, Eigen::Vector2d* grad = nullptr) const;

  double resolution() const { return resolution_; }
  /// Grid-frame position of the lower-left corner of cell (0, 0).
  const Eigen::Vector2d& origin() const { return origin_; }
  int width() const { return width_; }    ///< cells along x
  int height() const { return height_; }  ///< cells along y
  /// Cell containing p (may be outside [0, width) x [0, height)).
  CellIndex cellIndex(const Eigen::Vector2d& p) const;
  /// Grid-frame centre of cell (x, y).
  Eigen::Vector2d cellCenter(int x, int y) const;
  /// Bounding box (inclusive cell indices) of the known cells; false if nothing is known.
  bool knownBounds(CellIndex& min, CellIndex& max) const;
  /// Number of observed cells.
  std::size_t knownCells() const;
  const ProbabilityGridOptions& options() const { return options_; }

  /// Shrinks the grid to its known cells and frees the insertion scratch (called when a submap finishes;
  /// inserting again afterwards still works).
  void crop();
  /// Raw cell storage (row-major, y * width + x): P(occupied), 0 = unknown.
  const std::vector<float>& cells() const { return cells_; }

 private:
  void growToInclude(const Eigen::Vector2d& min, const Eigen::Vector2d& max);
  std::size_t flat(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
  }

  double resolution_;
  ProbabilityGridOptions options_;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  int width_ = 0, height_ = 0;
  std::vector<float> cells_;  ///< P(occupied); 0 = unknown
  float min_value_;
  // Insertion scratch: a cell is updated at most once per insertion (mark == epoch).
  std::vector<std::uint8_t> marks_;
  std::uint8_t epoch_ = 0;
  double odds_hit_, odds_miss_;
};

/// A local map: a probability grid whose frame sits at local_pose in the local SLAM frame.
struct Submap {
  Pose2 local_pose;  ///< grid frame in the local SLAM frame (translation of the first scan, theta = 0)
  ProbabilityGrid grid;
  int num_scans = 0;
  bool finished = false;
  int index = 0;     ///< 0, 1, 2, ... in creation order (LocalSlam)
};

}  // namespace cairn::graph_slam
