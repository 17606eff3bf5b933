// Person-masking scan filter (Yuan §3.2.1): the area of a tracked person is a circle of radius r_P around the
// person position; every beam between the two tangents from the sensor to that circle is marked invalid, so
// SLAM and the local planner do not see the person's legs.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "cairn/people_tracking/scan.hpp"

namespace cairn::people_tracking {

struct MaskParams {
  double leg_radius = 0.08;       // m, added to half the leg separation
  double margin = 0.10;           // m, safety margin
  double default_radius = 0.45;   // m, r_P when the leg separation is unknown
  double min_radius = 0.30;       // m
};

// r_P from the leg spacing (Yuan §3.2.1 footnote 4: obtainable from the distance between the two legs).
double personRadius(double leg_separation, const MaskParams& params = {});

struct MaskCircle {
  Eigen::Vector2d center;  // sensor frame
  double radius = 0.0;
};

enum class MaskMode {
  // Yuan §3.2.1: every beam between the two tangents is invalid, whatever it hit.
  kTangents,
  // Only beams whose return lies inside the circle (cairn's variant, not in the thesis): beams that pass beside
  // or between the person's legs, or end at something in front of the person, keep their static return, so
  // the mask takes no wall or furniture out of the scan. A beam without return (NaN/inf) is kept as it is.
  kReturnsInside,
};

// Beams whose bearing lies within asin(r / d) of the circle's bearing are set to NaN (ROS: invalid reading);
// with kReturnsInside only those of them whose return point lies inside the circle.
// A sensor inside a circle: kTangents masks the half plane towards its centre, kReturnsInside every return inside
// the circle (behind the sensor too). Returns the number of beams masked.
std::size_t maskScan(LaserScan& scan, const std::vector<MaskCircle>& circles, MaskMode mode = MaskMode::kTangents);

// "tangents" | "inside"; throws InputError naming `key` otherwise.
MaskMode parseMaskMode(const std::string& value, const std::string& key);

}  // namespace cairn::people_tracking
