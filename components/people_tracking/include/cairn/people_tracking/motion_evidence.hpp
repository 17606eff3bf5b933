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
#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

#include "cairn/people_tracking/scan.hpp"

namespace cairn::people_tracking {

struct MotionEvidenceParams {
  double window = 1.0;    // s, earlier scans consulted (0 disables: no evidence, the classifier alone decides)
  double min_age = 0.15;  // s, scans newer than this are not consulted (a stance foot has not moved yet)
  double margin = 0.15;   // m, an earlier beam must end this far behind the point to count as passing through it
  // A return stands for its surface at its own bearing only. Where the surface's range falls towards the point
  // (the beam's neighbour on the other side lies farther, by less than memory_surface_gap: one surface), the beam
  // must end `margin` behind the point after its range is brought nearer by this times that step times the
  // point's bearing offset from the beam (in beams). A wall seen at a grazing angle comes decimetres nearer within
  // one beam: without this, a wall's first returns after a door opening, seen from a robot driving down a corridor,
  // were "free" (the beam on one side had gone through the opening, the one on the other side hit the wall
  // 0.1-0.3 m beyond the point), formed moving clusters and started tracks (docs/benchmarks.md "Corridor walls").
  // 0 disables. Our choice (1: the linear extrapolation).
  double slope_factor = 1.0;
  // A point is free when at least this many of the consulted scans saw it so. One is not enough for clusters of one
  // or two points: a single missing return (the simulator's 0.2 % dropouts; on real lasers dark or specular surfaces
  // at grazing angles) reads as "no return within range", i.e. free, and a door frame seen edge-on then looked like
  // a moving leg and started tracks (office world, 27 runs: FP 11 338 -> 24 406 with 1, see docs/benchmarks.md
  // "Moving legs start tracks"). A walking person's legs stand where most of the window's scans saw free space.
  std::size_t min_free_scans = 2;
  std::size_t max_scans = 64;  // kept at most (fast lasers: the oldest are dropped first)
  // Free-space memory (FreeSpaceMemory below): a place the beams crossed within the last `memory` seconds is not
  // static background. 0 disables it.
  double memory = 60.0;            // s
  double memory_resolution = 0.1;  // m, grid cell (at most the beam spacing at the detector's range: 5.8 cm at 10 m
                                   // and 0.33 deg, so that every cell there is crossed by some beam)
  double memory_size = 40.0;       // m, side of the square grid kept around the sensor; rays are followed to a quarter
                                   // of it (10 m: the detector's max_range)
  // m, consecutive returns closer than this are one surface: the cells between them are not free (a wall seen at a
  // grazing angle), and slope_factor extrapolates across it. Our choice: at 8 m and 0.33 deg a wall's returns are
  // 1 m apart at 2.7 deg incidence.
  double memory_surface_gap = 1.0;
};

// Where the beams have gone through, remembered for a long time: the static background (walls, furniture) is never
// free, the place a person stands on was free before the person came (unless the person stood there, hidden or out
// of range, since the sensor first looked). A grid in the tracking frame counts per cell the scans that saw it free
// -- a beam crossed the whole cell and ended at least `margin` beyond it (ray traversal, Amanatides & Woo 1987)
// while no return of that scan lay in the cell, its eight neighbours, or on the surface between two consecutive
// returns less than `surface_gap` apart -- and the scans with such a return. A cell is free when it was seen free
// in at least `min_free_scans` scans, in more scans than it had a return, and within `memory` seconds; a place is
// free when its cell and the eight around it are. Each rule is there for a case (tests FreeSpaceMemory.*): a chair
// leg thinner than a cell has its cells crossed by the beams passing on both sides of it (the neighbour rule); a
// wall seen at a grazing angle has returns decimetres apart and the beams graze the cells between them (the surface
// rule); behind a door opening, a corridor wall's cells are crossed through the opening in the scans where a person
// hides the wall's returns (the count); a box's corner seen at a grazing angle has a return in every other scan and
// is crossed in the others (the place rule: the box's inside is never free). A beam without a return
// (LaserScan::beyondRange: nothing within range_max) crosses up to range_max, or up to a neighbouring beam's return
// when it has one (a single missing return on a wall must not cross the wall); NaN and returns below range_min give
// no information.
// Limits: a face of a wide object first seen from a new viewpoint, whose cells the beams grazing its corners crossed
// before, can read as free until it has been seen as often; a person standing still longer than the place was
// seen free before becomes background. The grid follows the sensor: when the sensor leaves the middle half, the
// grid is moved by whole cells (cells that fall outside are forgotten). Not from the seeds: the static map the
// tracker otherwise needs (SPENCER; "Weak legs with a static map" in docs/benchmarks.md), learned from the scans
// alone, in the spirit of the free-space evidence of occupancy-grid mapping.
class FreeSpaceMemory {
 public:
  // Throws InputError unless resolution > 0, 4 * resolution <= size <= 4000 * resolution, margin >= 0, memory >= 0,
  // surface_gap >= 0 and min_free_scans >= 1.
  FreeSpaceMemory(double resolution, double size, double margin, double memory, std::size_t min_free_scans,
                  double surface_gap);
  // Marks the cells the scan saw free (sensor pose in the tracking frame). A stamp before the newest added clears
  // the memory first (time went backwards). The scan must have passed validateScan; a pose that is not finite or
  // beyond 1e9 m is ignored.
  void add(const LaserScan& scan, const Pose2& sensor_pose);
  // Whether the cell holding p (tracking frame) and its eight neighbours were each seen free (above) within
  // [stamp - memory, stamp].
  [[nodiscard]] bool seenFree(const Eigen::Vector2d& p, double stamp) const;
  [[nodiscard]] bool enabled() const { return memory_ > 0.0; }
  void clear();

 private:
  void follow(const Eigen::Vector2d& sensor);  // moves the grid so that the sensor is in its middle half
  [[nodiscard]] long cellIndex(const Eigen::Vector2d& p) const;  // -1 outside the grid
  // Visits the cells a ray from `from` (tracking frame) crosses completely within `length`.
  template <typename Visit>
  void cross(const Eigen::Vector2d& from, double angle, double length, Visit&& visit) const;

  double resolution_, size_, margin_, memory_, surface_gap_;
  std::uint16_t min_free_scans_;
  int cells_ = 0;  // per side
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();  // tracking-frame corner of cell (0, 0)
  struct Cell {
    float last_free = 0.0F;         // stamp (seconds after epoch_) of the last scan that saw the cell free
    std::uint16_t near_scans = 0;   // scans with a return in the cell or a neighbour
    std::uint16_t free_scans = 0;   // scans that saw the cell free
  };
  static void count(std::uint16_t& counter, Cell& cell);  // +1, both halved first when it would overflow
  std::vector<Cell> grid_;
  // Per scan, one bit per cell: a return in the cell or a neighbour (not free in this scan); seen free already.
  std::vector<std::uint64_t> near_now_, crossed_now_;
  static void set(std::vector<std::uint64_t>& bits, std::size_t i) { bits[i >> 6] |= std::uint64_t{1} << (i & 63); }
  double epoch_ = 0.0, newest_ = 0.0;  // float stamps keep sub-millisecond resolution relative to the epoch
  bool empty_ = true;
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
  // Whether the beams crossed the place of `p` (tracking frame) within the last `memory` seconds: not part of the
  // static background (FreeSpaceMemory). False with memory 0.
  [[nodiscard]] bool crossedBefore(const Eigen::Vector2d& p, double stamp) const {
    return memory_.seenFree(p, stamp);
  }
  [[nodiscard]] bool remembersFreeSpace() const { return memory_.enabled(); }
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
  FreeSpaceMemory memory_;
};

}  // namespace cairn::people_tracking
