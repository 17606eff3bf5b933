// Fusion of person detections from several sources (e.g. two lasers now, a camera later), Stüde §2.1.3:
// between two sources with overlapping fields of view, the pairs with minimum Euclidean distance are fused by
// a weighted average (here the information-weighted average, i.e. weights are the inverse covariances);
// detections without a partner are appended unchanged (the thesis' "aggregation").
#pragma once

#include <utility>
#include <vector>

#include "cairn/people_tracking/detector.hpp"

namespace cairn::people_tracking {

struct FusionParams {
  double max_pair_distance = 0.5;  // m, detections farther apart are never fused
  // > 0: pairs must also lie within this Mahalanobis distance (d^2 with the sum of both covariances) and are
  // taken smallest d^2 first — for sources whose errors are far from round (a camera's range error); 0: the
  // thesis' Euclidean nearest pairs.
  double gate_chi2 = 0.0;
};

// All detections must be in one common frame. Sources are folded in order: fuse(fuse(s0, s1), s2) ...
std::vector<PersonDetection> fuseDetections(const std::vector<std::vector<PersonDetection>>& sources,
                                            const FusionParams& params = {});

// The pairs (index in a, index in b) that fuseDetections fuses: repeatedly the globally closest unused pair
// within max_pair_distance (and gate_chi2).
std::vector<std::pair<std::size_t, std::size_t>> nearestPairs(const std::vector<PersonDetection>& a,
                                                              const std::vector<PersonDetection>& b,
                                                              const FusionParams& params = {});

// Information-weighted average of two detections (covariances must be positive definite).
PersonDetection fusePair(const PersonDetection& a, const PersonDetection& b);

}  // namespace cairn::people_tracking
