// Motion evidence from the scan history: was a point seen as free space a moment ago?
//
// The leg classifier looks at one cluster in one scan. At 6-8 m a leg is 2-4 beams wide and its shape says little
// (docs/benchmarks.md "third round": the classifier finds a leg of a counted person in 63 % of the scans there),
// and lowering its threshold lets chair and table legs in (office world: more false tracks and switches). What it
// cannot see is time: a walking person's legs stand where, a fraction of a second before, the beams went through
// to something behind them; furniture and walls stand where the beams always ended. This keeps the last scans with
// the sensor pose of each, and for a point of the current scan (tracking frame) asks whether an earlier scan's
// beams towards it both passed it by more than a margin (negative information, as the tracker's free-space test
// uses it for tracks). The share of a cluster's points seen free is its motion evidence; the detector lets moving
// clusters with a lower classifier score through (DetectorParams::moving_*).
//
// Geometry only, per beam, no grid: the two beams bracketing the point's bearing must both end beyond it, so a
// wall seen at a grazing angle (where one bracketing beam hits the wall before the point and one after it) is
// never called free, and a single dropout is not either. Occluded in an earlier scan (a nearer return): no
// information. A person standing still for longer than `window` gives no evidence: the classifier alone decides,
// as without this. Not from the seeds (Stüde §2.1.3 and Yuan §2.2.1 detect legs per scan); the idea is the
// moving-object detection of occupancy-grid trackers (e.g. Schulz et al. 2003, Wang et al. 2007) without the grid.
#pragma once

#include <Eigen/Core>
#include <deque>
#include <vector>

#include "cairn/people_tracking/scan.hpp"

namespace cairn::people_tracking {

struct MotionEvidenceParams {
  double window = 1.0;    // s, earlier scans consulted (0 disables: no evidence, the classifier alone decides)
  double min_age = 0.15;  // s, scans newer than this are not consulted (a stance foot has not moved yet)
  double margin = 0.15;   // m, an earlier beam must end this far behind the point to count as passing through it
  // A point is free when at least this many of the consulted scans saw it so. One is not enough for clusters of one
  // or two points: a single missing return (the simulator's 0.2 % dropouts; on real lasers dark or specular surfaces
  // at grazing angles) reads as "no return within range", i.e. free, and a door frame seen edge-on then looked like
  // a moving leg and started tracks (office world, 27 runs: FP 11 338 -> 24 406 with 1, see docs/benchmarks.md
  // "Moving legs start tracks"). A walking person's legs stand where most of the window's scans saw free space.
  std::size_t min_free_scans = 2;
  std::size_t max_scans = 64;  // kept at most (fast lasers: the oldest are dropped first)
};

class MotionEvidence {
 public:
  explicit MotionEvidence(MotionEvidenceParams params = {});

  // Remember a scan (after its clusters were scored) with the sensor pose in the tracking frame at its stamp.
  // A stamp not after the newest kept scan clears the history first (time went backwards or a repeated scan).
  // Throws InputError on malformed scan metadata.
  void add(const LaserScan& scan, const Pose2& sensor_pose);
  // Share of `points` (tracking frame) that an earlier scan, taken in [stamp - window, stamp - min_age], saw as
  // free space. 0 for no points or no usable history. With `stop_below` > 0 the count stops as soon as the share
  // cannot reach it any more (then the result is a lower bound below stop_below): most clusters are walls and
  // furniture, and their points would otherwise be checked against every earlier scan.
  [[nodiscard]] double freeFraction(const std::vector<Eigen::Vector2d>& points, double stamp,
                                    double stop_below = 0.0) const;
  // Whether one earlier scan saw `p` (tracking frame) as free space.
  [[nodiscard]] bool seenFree(const Eigen::Vector2d& p, double stamp) const;
  [[nodiscard]] std::size_t size() const { return history_.size(); }

 private:
  struct Past {
    LaserScan scan;
    Pose2 pose;
    double cos_theta = 1.0, sin_theta = 0.0;  // of pose.theta, for the tracking -> sensor transform
    bool full_circle = false;
  };
  [[nodiscard]] bool freeIn(const Past& past, const Eigen::Vector2d& p) const;

  MotionEvidenceParams params_;
  std::deque<Past> history_;
};

}  // namespace cairn::people_tracking
