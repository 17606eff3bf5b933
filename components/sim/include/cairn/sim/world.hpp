// World description: static walls (line segments and/or an occupancy image), named regions, doors and
// furniture that change on a schedule, retro-reflective markers, robot start, routes and people.
// The YAML format is documented in components/sim/README.md ("World format").
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/sim/types.hpp"

namespace cairn::sim {

/// Error in a world (or other input) file; what() is "<file>:<line>: <message>" (line is 1-based).
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string message_;
};

/// Named polygonal region (room, corridor, kitchen, ...).
struct Region {
  std::string name;
  std::vector<Vec2> polygon;
  bool contains(Vec2 p) const;
  Vec2 centroid() const;
};

/// A switch schedule: sorted (time, state index) entries; with period > 0 the schedule repeats.
/// The state before the first entry is the last entry's state of the previous period (or entry 0
/// without period).
struct Schedule {
  std::vector<double> times;
  double period = 0.0;
  /// Index of the entry in force at time t (0 if empty).
  std::size_t indexAt(double t) const;
};

/// A door: a panel from hinge to latch (closed position). Open means swung by open_angle about the hinge.
struct Door {
  std::string name;
  Vec2 hinge;
  Vec2 latch;
  double open_angle = 1.5707963267948966;  ///< rad, positive = counter-clockwise
  double thickness = 0.04;
  float reflectivity = 0.3F;
  Schedule schedule;
  std::vector<bool> open;  ///< state per schedule entry; empty schedule -> initially_open
  bool initially_open = false;
  bool isOpen(double t) const;
  /// The panel as a segment at time t.
  Segment panel(double t) const;
};

/// A movable rectangular piece of furniture (box, shelf, table). With legs_only the laser sees only
/// four leg circles at the corners (a table: Yuan §4.2.3 — only the four small table legs are perceived).
struct Furniture {
  std::string name;
  double length = 1.0;  ///< along the local x axis
  double width = 0.5;
  bool legs_only = false;
  double leg_radius = 0.025;
  float reflectivity = 0.3F;
  Schedule schedule;
  std::vector<Pose2> poses;  ///< pose per schedule entry (centre of the rectangle)
  /// false: jumps to each scheduled pose (semi-static objects); true: moves linearly between consecutive
  /// poses (continuously moving "dynamic objects" of Dörr §6.2.2).
  bool interpolate = false;
  Pose2 poseAt(double t) const;
  /// Appends the laser-visible geometry at time t.
  void geometry(double t, std::vector<Segment>& segments, std::vector<Circle>& circles) const;
};

/// Retro-reflective marker: a reflector post of radius `radius` (reflectivity 1). Dörr §4.4 uses
/// binary reflectivity (low/high); markers are the "high" class.
struct Marker {
  std::string name;
  Vec2 position;
  double radius = 0.04;
  float reflectivity = 1.0F;
};

/// Recorded or scripted people that the world brings along (see people.hpp for the models).
struct PeopleSource {
  std::string kind;  ///< "scripted", "csv", "eth_obsmat", "edinburgh"
  std::string file;  ///< resolved path (recorded kinds)
  std::vector<Vec2> waypoints;  ///< scripted: walk along these (loop), speed below
  double speed = 1.0;
  double start_time = 0.0;
  Pose2 offset;       ///< recorded: world = offset ⊕ (scale * data)
  double scale = 1.0;
  double time_offset = 0.0;
  double frame_period = 0.0;  ///< eth_obsmat / edinburgh: seconds per frame number (0 = format default)
  bool loop = false;
};

/// Crowd model (schedule-driven): people appear at sources with a time-varying Poisson rate and walk to
/// sinks along free space.
struct CrowdConfig {
  struct RateTerm {
    double period = 86400.0;  ///< s
    double amplitude = 0.0;   ///< relative to base rate
    double phase = 0.0;       ///< s: time of the peak within the period
  };
  std::vector<std::string> sources;  ///< region names (people appear at the centroid ± jitter)
  std::vector<std::string> sinks;    ///< region names (goal chosen uniformly)
  double base_rate = 0.0;            ///< people per hour at each source
  std::vector<RateTerm> terms;       ///< rate(t) = base * max(0, 1 + sum a cos(2 pi (t - phase) / period))
  /// Walking speeds are drawn from N(speed, speed_sigma) clamped to [kMinSpeed, kMaxSpeed] m/s.
  static constexpr double kMinSpeed = 0.4, kMaxSpeed = 2.0;
  double speed = 1.1;
  double speed_sigma = 0.15;
  int max_people = 30;
  /// Schedule time at sim t = 0 (s): the rate terms see t + start_time, e.g. 201600 = Wednesday 08:00 when the
  /// weekly term's t = 0 is Monday 00:00.
  double start_time = 0.0;
  /// Rate (people/s) at one source at sim time t.
  double rateAt(double t) const;
};

struct World {
  std::string name;
  std::string file;  ///< path the world was loaded from ("" if built in code)
  std::vector<Segment> walls;  ///< static geometry (segments from the YAML plus occupancy-image edges)
  std::vector<Region> regions;
  std::vector<Door> doors;
  std::vector<Furniture> furniture;
  std::vector<Marker> markers;
  Pose2 robot_start;
  std::map<std::string, std::vector<Vec2>> routes;
  std::vector<PeopleSource> people;
  std::optional<CrowdConfig> crowd;
  Vec2 bounds_min, bounds_max;  ///< axis-aligned bounds of the static geometry

  const Region* region(const std::string& name) const;
  /// Name of the first region containing p, or "".
  std::string regionAt(Vec2 p) const;
  /// Doors, furniture and markers at time t (walls are static and not included).
  void dynamicGeometry(double t, std::vector<Segment>& segments, std::vector<Circle>& circles) const;
  void computeBounds();
};

/// Loads a world YAML file. Throws InputError naming file:line and the offending key.
World loadWorld(const std::string& path);
/// Parses world YAML text; `file` is used for error messages and for resolving relative paths.
World parseWorld(const std::string& yaml_text, const std::string& file);

/// Occupancy image (ROS map_server convention): pixel (0,0) is the top-left corner; the bottom-left
/// corner of the image is at `origin`; p = (255 - value) / 255 (negate flips it); p > occupied_thresh
/// is occupied.
struct OccupancyImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  ///< row-major, 8-bit grey
};
/// Reads an 8-bit PGM (P5/P2) or PNG (any colour type, converted to grey). Throws InputError.
OccupancyImage readImage(const std::string& path);
/// Boundary edges of occupied cells, merged into maximal collinear runs.
std::vector<Segment> occupancyToSegments(const OccupancyImage& img, double resolution, Pose2 origin,
                                         double occupied_thresh, bool negate, float reflectivity);

/// Resolves a world name ("office") or path ("x.yaml") to a file: an existing path is returned as is,
/// otherwise <dir>/<name>.yaml in $CAIRN_SIM_WORLDS, the source tree and the install tree.
std::string resolveWorldPath(const std::string& name_or_path);
/// Names of the worlds shipped with cairn_sim.
std::vector<std::string> shippedWorlds();

}  // namespace cairn::sim
