// Spatio-temporal gridding of people detections observed by a moving robot (Stüde 2024, §4.2.2).
//
// Every detection d = (x1, x2, t) falls into a cell S_i of edge r_s and time bin τ; each cell gets a count c_i
// and an observed duration Δ_i (time during which the cell centre was inside the robot's field of view: a
// circle of radius r_fov pruned by ray casting against the occupancy map). Targets are rates y_i = c_i / Δ_i
// (eqs. 4.5-4.6). The gridifier is streaming: only the open time bins are held in memory, finished bins are
// emitted by flush(), so memory is bounded by (#open bins) x (#cells visited per bin).
#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

namespace cairn::copa_map {

// Occupancy grid in the map frame (ROS map_server convention: cell (0,0) is at `origin`, row index grows
// with x2).
struct OccupancyMap {
  int width = 0;
  int height = 0;
  double resolution = 0.05;  // m per cell
  double origin_x = 0.0;     // map frame position of cell (0,0)'s lower-left corner
  double origin_y = 0.0;
  std::vector<std::uint8_t> occupied;  // width*height, row-major (row = x2 index), 1 = obstacle

  bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < width && cy < height; }
  bool occupiedCell(int cx, int cy) const {
    return inside(cx, cy) && occupied[static_cast<std::size_t>(cy) * width + cx] != 0;
  }
  bool occupiedAt(double x, double y) const;
  // True when the straight segment (x0,y0)->(x1,y1) crosses no occupied map cell (the start cell, which holds
  // the sensor, is not checked). Exact grid traversal (Amanatides & Woo).
  bool lineOfSight(double x0, double y0, double x1, double y1) const;
};

struct GridConfig {
  double cell_size = 0.5;        // r_s [m] (ATC benchmark: 0.5 m)
  double time_bin = 3600.0;      // τ [s] (ATC benchmark: 60 min)
  double origin_x = 0.0;         // lower-left corner of cell (0,0) [m]
  double origin_y = 0.0;
  int nx = 0;                    // number of cells along x1, x2 (detections outside are ignored)
  int ny = 0;
  double t_origin = 0.0;         // start of time bin 0 [s]
  double fov_radius = 3.5;       // r_fov [m] (copa-map util/fov.py; the thesis does not state it)
  double max_pose_gap = 1.0;     // a pose is held at most this long [s] (gaps in the pose stream are unobserved)
  double min_duration = 20.0;    // cells observed less than this [s] are dropped (copa-map Gridifier)
  double rate_unit = 3600.0;     // y = c / (Δ / rate_unit): rate per hour by default
  double rate_min = 1e-6;        // target for c = 0 (copa-map rate_min)
};

struct GridCell {
  int ix = 0, iy = 0;
  std::int64_t bin = 0;
  double x1 = 0, x2 = 0;  // cell centre [m]
  double t = 0;           // time bin index (centre convention of copa-map data: the bin's index)
  double count = 0;       // c_i
  double duration = 0;    // Δ_i [s], 0 < Δ_i <= τ
  double rate = 0;        // y_i = c_i / Δ_i (eq. 4.6) in counts per rate_unit
};

struct GridifierStats {
  std::uint64_t detections_counted = 0;
  std::uint64_t detections_outside_grid = 0;
  std::uint64_t detections_late = 0;        // arrived for an already emitted bin
  std::uint64_t detections_unobserved = 0;  // cell not (or too briefly) in the field of view
  std::uint64_t cells_dropped_short = 0;
};

class Gridifier {
 public:
  explicit Gridifier(GridConfig config, std::shared_ptr<const OccupancyMap> map = nullptr);

  // Robot position at time t (non-decreasing; a pose is held until the next one, at most max_pose_gap).
  void addPose(double t, double x, double y);
  // A people detection at (x, y) and time t (map frame). It is counted only if its cell was in the field of view at
  // t: within a credited visibility interval, or visible from the latest pose (t no more than max_pose_gap after it);
  // otherwise it is unobserved (a tracker that sees beyond fov_radius must not inflate c_i against Δ_i).
  void addDetection(double t, double x, double y);
  // Emits all bins that end at or before min(t, last pose time); their memory is released.
  std::vector<GridCell> flush(double t);
  // Emits all remaining bins.
  std::vector<GridCell> finish();

  // Linear indices (iy*nx+ix) of the grid cells visible from (x, y): centre within r_fov and in line of sight.
  std::vector<int> visibleCells(double x, double y) const;

  std::size_t openEntries() const;
  const GridifierStats& stats() const { return stats_; }
  const GridConfig& config() const { return config_; }

 private:
  struct Accumulator {
    double count = 0;
    double duration = 0;
    // When the cell was in the field of view within this bin: merged [from, to] intervals (one per uninterrupted
    // stretch). A detection counts only at a time the cell was seen (Stüde §4.2.2: c_i and Δ_i of the visible cell).
    std::vector<std::pair<double, double>> seen;
  };
  using BinMap = std::unordered_map<int, Accumulator>;
  void creditDuration(double t0, double t1, const std::vector<int>& cells);
  std::int64_t binOf(double t) const;
  void emitBin(std::int64_t bin, BinMap& cells, std::vector<GridCell>& out);

  GridConfig config_;
  std::shared_ptr<const OccupancyMap> map_;
  std::unordered_map<std::int64_t, BinMap> bins_;
  bool have_pose_ = false;
  double last_t_ = 0, last_x_ = 0, last_y_ = 0;
  std::vector<int> last_visible_;
  std::int64_t emitted_up_to_ = INT64_MIN;  // bins < this value have been emitted
  GridifierStats stats_;
};

}  // namespace cairn::copa_map
