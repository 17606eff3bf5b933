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

// An exchange of two people's ids in a recording: the annotations of `a` after time `after` are the continuation
// of `b`'s path and vice versa (the annotator swapped two people walking side by side; replayed as recorded, they
// trade places through each other within one annotation period).
struct IdExchange {
  int a = 0, b = 0;
  double after = 0.0;  // s, the last annotation time before the exchange
};
struct IdExchangeParams {
  double max_distance = 1.5;           // m, the two people this close at `after`
  double ratio = 0.25;                 // exchanged / recorded second differences (squared, summed over both)
  double min_second_difference = 0.2;  // m, the recorded paths' second difference (root of the sum) at least this
};
// Finds such exchanges from the annotations alone and undoes them in place, earliest first: at an annotation time
// t where two people have annotations at t and at the same neighbouring times (no gap > max_gap), their paths'
// second differences p(t-) - 2 p(t) + p(t+) as recorded and with the two ids exchanged after t are compared; an
// exchange is undone when it makes both paths much smoother (params). A constant-velocity crossing, a group walking
// together or one person turning does not qualify (the recorded paths are already smooth, or exchanging does not
// smooth them). Returns the exchanges undone. The points' set (hence t_begin/t_end/min/max) does not change.
// Diagnostic (bench --fix-id-swaps); ETH/UCY: three in seq_eth and seq_hotel, docs/benchmarks.md.
std::vector<IdExchange> fixIdExchanges(TrajectorySet& set, const IdExchangeParams& params = {});

}  // namespace cairn::people_tracking
