// Recorded pedestrian trajectories: ETH/UCY obsmat.txt, Edinburgh Informatics Forum tracks.*.txt, and CSV
// `t,id,x,y` (seconds, metres). Positions are interpolated linearly between annotations.
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cairn::people_tracking {

struct TrajectoryPoint {
  double t = 0.0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
};

struct TrajectorySet {
  std::string format;                                  // "obsmat" | "edinburgh" | "csv"
  std::map<int, std::vector<TrajectoryPoint>> people;  // sorted by time
  double t_begin = 0.0, t_end = 0.0;
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
  double max_gap = 1.0;  // s, a person is absent between annotations further apart than this

  // Interpolated position, or nothing outside the person's annotated span / inside a gap.
  [[nodiscard]] std::optional<Eigen::Vector2d> positionAt(int id, double t) const;
  [[nodiscard]] std::size_t samples() const;
};

// Format by content: "TRACK." lines -> Edinburgh (24.7 mm/pixel, 9 frames/s, per the shared data README);
// commas -> CSV (optional header); otherwise whitespace obsmat `frame id x z y vx vz vy` with the annotation
// period 0.4 s mapped onto the smallest frame step. Throws InputError naming file and line on bad input.
TrajectorySet loadTrajectories(const std::string& path);

}  // namespace cairn::people_tracking
