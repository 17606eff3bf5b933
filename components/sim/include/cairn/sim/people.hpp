// Simulated people: two-legged walkers (each leg a small circle swinging with the gait phase, so a laser
// sees leg pairs), driven by recorded trajectories, scripted waypoints or a schedule-driven crowd model.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cairn/sim/raycast.hpp"
#include "cairn/sim/rng.hpp"
#include "cairn/sim/types.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// Leg geometry and gait. Legs sit at ±hip_half_width left/right of the walking direction; while walking
/// they swing fore and aft in antiphase, x_leg = ±swing(v) sin(phase); the phase advances by 2 pi per
/// stride (two steps). A standing person keeps both legs side by side.
struct GaitConfig {
  double leg_radius = 0.06;
  double hip_half_width = 0.1;
  double stride_length = 1.3;     ///< m per gait cycle (two steps) at normal speed
  double swing_amplitude = 0.3;   ///< m, fore/aft leg excursion at speeds >= swing_speed
  double swing_speed = 1.0;       ///< m/s
};

/// Social force between walkers that follow paths (scripted and crowd; recorded people replay their data),
/// Helbing & Molnár 1995: dv/dt = (v0 e - v)/tau + Σ w(φ) A exp((r_ij - d_ij)/B) n_ij, with the anisotropy
/// w(φ) = λ + (1-λ)(1+cos φ)/2 (others ahead count more), d_ij taken at the predicted closest approach
/// (Zanlungo, Ikeda & Kanda 2011) so that walkers on a collision course turn away early. The robot repels like a person of radius
/// robot_radius. A tangential term pushes to the walker's right when someone is ahead, which breaks the
/// exact head-on symmetry (a convention, not in the paper). Integrated in steps of at most max_step.
struct SocialForceConfig {
  bool enabled = true;
  double body_radius = 0.25;     ///< m, r_i
  double strength = 2.0;         ///< A, m/s² (Helbing & Molnár use 2.1)
  double range = 0.3;            ///< B, m
  double tau = 0.5;              ///< s, relaxation time
  double anisotropy = 0.35;      ///< λ
  double keep_right = 0.5;       ///< tangential share of the repulsion from someone ahead
  double interaction_radius = 3.0;  ///< m; with nobody nearer a walker follows its path exactly
  double prediction_horizon = 1.5;  ///< s, repulsion evaluated at the predicted closest approach (Zanlungo 2011)
  double max_speed_factor = 1.3; ///< |v| <= factor × desired speed
  double waypoint_tolerance = 0.4;  ///< m, a path point counts as reached
  double max_step = 0.05;        ///< s, integration step
};

/// Leg centres for a person at `position` walking along `heading` with `speed` at gait `phase`.
void legPositions(const GaitConfig& gait, Vec2 position, double heading, double speed, double phase, Vec2 legs[2]);

/// A recorded trajectory: samples sorted by time.
struct Trajectory {
  int id = 0;
  std::vector<double> t;
  std::vector<Vec2> p;
  double start() const { return t.front(); }
  double end() const { return t.back(); }
  /// Linear interpolation; velocity from the enclosing samples. Requires start() <= time <= end().
  void sample(double time, Vec2& pos, Vec2& vel) const;
};

/// Plain CSV `t,id,x,y` (seconds, integer id, metres), one sample per line, optional header line,
/// '#' comments. Throws InputError with file:line.
std::vector<Trajectory> loadTrajectoriesCsv(const std::string& path);
/// ETH/UCY obsmat.txt: `frame ped_id pos_x pos_z pos_y v_x v_z v_y`; t = frame * frame_period
/// (default 0.4 s / 6 frames: ETH annotations every 6th frame at 2.5 fps).
std::vector<Trajectory> loadEthObsmat(const std::string& path, double frame_period = 0.4 / 6.0);
/// Edinburgh Informatics Forum `TRACK.Rk=[[x y t];...];` in image pixels (24.7 mm/pixel) and frames
/// (default 1/9 s); returned in metres and seconds.
std::vector<Trajectory> loadEdinburghTracks(const std::string& path, double frame_period = 1.0 / 9.0,
                                            double metres_per_pixel = 0.0247);
/// The trajectories of a recorded people source (csv, eth_obsmat, edinburgh) of a world, placed by its offset,
/// scale and time offset. A file without any trajectory (e.g. the wrong `kind`) throws InputError too.
std::vector<Trajectory> loadPeopleSource(const PeopleSource& source);
/// world = offset ⊕ (scale * p), t + time_offset.
void transformTrajectories(std::vector<Trajectory>& trajs, const Pose2& offset, double scale, double time_offset);

/// Occupancy grid of the static walls (plus static furniture) inflated by a clearance, with A* search;
/// used by the crowd model to walk "along free space".
class FreeSpaceGrid {
 public:
  FreeSpaceGrid(const World& world, double resolution = 0.2, double clearance = 0.3);
  bool free(Vec2 p) const;
  /// Shortest 8-connected path from a to b through free cells, shortcut by line of sight; empty if none.
  std::vector<Vec2> plan(Vec2 a, Vec2 b) const;
  /// Doors closed at time t block their doorway for the following plan() calls.
  void setDoorTime(const World& world, double t);
  /// A random free point inside the region (rejection sampling); returns false if none found.
  bool samplePoint(const Region& region, Rng& rng, Vec2& out) const;

 private:
  int index(int cx, int cy) const { return cy * nx_ + cx; }
  bool cellFree(int cx, int cy) const {
    if (cx < 0 || cy < 0 || cx >= nx_ || cy >= ny_) return false;
    const int i = index(cx, cy);
    return !blocked_[i] && (door_of_cell_[i] < 0 || !door_closed_[static_cast<std::size_t>(door_of_cell_[i])]);
  }
  bool lineFree(Vec2 a, Vec2 b) const;
  double res_;
  Vec2 min_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint8_t> blocked_;
  std::vector<int> door_of_cell_;    ///< door whose closed panel blocks the cell, or -1
  std::vector<bool> door_closed_;
};

/// All people of a world at the current sim time. Deterministic for a given seed.
class PeopleSimulator {
 public:
  /// enable_sources: the world's recorded/scripted people; enable_crowd: its crowd model (if any).
  PeopleSimulator(const World& world, GaitConfig gait, Rng rng, bool enable_sources = true, bool enable_crowd = true);
  /// Advances people to absolute time t (>= the previous t).
  void update(double t);
  const std::vector<PersonState>& people() const { return people_; }
  /// Leg circles of all people (appends).
  void legCircles(std::vector<Circle>& out) const;
  /// Adds recorded trajectories (already in world coordinates).
  void addTrajectories(std::vector<Trajectory> trajs, bool loop);
  /// Adds a scripted walker along waypoints (loops) at `speed`, appearing at `start_time`.
  void addScripted(std::vector<Vec2> waypoints, double speed, double start_time);
  int spawnedCrowd() const { return spawned_; }
  void setSocialForce(const SocialForceConfig& c) { social_ = c; }
  const SocialForceConfig& socialForce() const { return social_; }
  /// The robot, repelling walkers (social force) from the next update() on; radius 0 = no robot.
  void setRobot(Vec2 position, double radius) {
    robot_pos_ = position;
    robot_radius_ = radius;
  }

 private:
  struct Agent {
    int id = 0;
    enum class Kind { Recorded, Scripted, Crowd } kind = Kind::Scripted;
    const Trajectory* traj = nullptr;
    bool loop = false;
    std::vector<Vec2> path;   // scripted / crowd
    std::size_t next = 1;     // next path point
    double speed = 1.0;
    double start_time = 0.0;
    Vec2 pos;
    Vec2 vel;                 // social-force velocity
    double heading = 0.0;
    double phase = 0.0;
    bool active = false;
    bool done = false;
  };
  void spawnCrowd(double t0, double t1);
  void moveAlongPath(Agent& a, double dt);
  bool followsPath(const Agent& a, double t) const;
  void socialStep(double t, double h);

  const World& world_;
  GaitConfig gait_;
  Rng rng_;
  std::vector<std::unique_ptr<Trajectory>> trajectories_;
  std::vector<Agent> agents_;
  std::vector<PersonState> people_;
  std::unique_ptr<FreeSpaceGrid> free_;
  std::vector<double> next_arrival_;
  double t_ = 0.0;
  bool started_ = false;
  int next_id_ = 1;
  int spawned_ = 0;
  bool crowd_ = false;
  SocialForceConfig social_;
  Vec2 robot_pos_;
  double robot_radius_ = 0.0;
};

}  // namespace cairn::sim
