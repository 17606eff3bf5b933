// Fusion of person detections from several sources (e.g. two lasers now, a camera later), Stüde §2.1.3:
// between two sources with overlapping fields of view, the pairs with minimum Euclidean distance are fused by
// a weighted average (here the information-weighted average, i.e. weights are the inverse covariances);
// detections without a partner are appended unchanged (the thesis' "aggregation").
#pragma once

#include <vector>

#include "cairn/people_tracking/detector.hpp"

namespace cairn::people_tracking {

struct FusionParams {
  double max_pair_distance = 0.5;  // m, detections farther apart are never fused
};

// All detections must be in one common frame. Sources are folded in order: fuse(fuse(s0, s1), s2) ...
std::vector<PersonDetection> fuseDetections(const std::vector<std::vector<PersonDetection>>& sources,
                                            const FusionParams& params = {});

// Information-weighted average of two detections (covariances must be positive definite).
PersonDetection fusePair(const PersonDetection& a, const PersonDetection& b);

}  // namespace cairn::people_tracking
