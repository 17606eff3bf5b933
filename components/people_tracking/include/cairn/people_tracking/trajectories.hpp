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

// Smooths every person's annotations in place with a Gaussian-weighted local linear fit over time (kernel
// standard deviation `sigma` seconds, points within 3 sigma, never across a gap longer than max_gap). A local
// *linear* fit leaves constant-velocity motion unchanged, also at a track's ends (a weighted mean would pull the
// ends inwards). Purpose: hand-annotated positions (ETH/UCY: clicked at 2.5 Hz) carry a few centimetres of
// jitter, which linear interpolation replays as instantaneous velocity changes (ETH: up to 1.4 m/s between two
// scans, 99th percentile) that no walking person makes. Times, t_begin/t_end and min/max (the annotations'
// bounding box) stay as loaded. Throws InputError unless sigma is finite and > 0.
void smoothTrajectories(TrajectorySet& set, double sigma);

}  // namespace cairn::people_tracking
