// Small deterministic 2D scene generator and ray caster used for training data and evaluation until the
// simulator component is available: person legs (circles with a gait), table and chair legs, poles, walls,
// doors and clutter. Every beam remembers which object it hit, so clusters get ground-truth labels.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/segmentation.hpp"

namespace cairn::people_tracking {

enum class ObjectClass : std::uint8_t { kPersonLeg, kTableLeg, kChairLeg, kPole, kWall, kDoor, kClutter };
const char* toString(ObjectClass c);

struct SceneCircle {
  Eigen::Vector2d center;
  double radius = 0.0;
  int object = -1;
};
struct SceneSegment {
  Eigen::Vector2d a, b;
  int object = -1;
};

struct Scene {
  std::vector<SceneCircle> circles;
  std::vector<SceneSegment> segments;
  std::vector<ObjectClass> object_class;  // by object id
  std::vector<int> object_person;         // person id by object id (-1: not a person)

  int addObject(ObjectClass c, int person = -1);
  void addCircle(const Eigen::Vector2d& center, double radius, ObjectClass c, int person = -1);
  void addSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, ObjectClass c);
  void addBox(const Eigen::Vector2d& center, double half_x, double half_y, double yaw, ObjectClass c);
};

// A walking person: two legs beside the body centre, swinging along the heading (gait).
struct WalkerState {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // body centre
  double heading = 0.0;                                // rad
  double gait_phase = 0.0;                             // rad, advances 2*pi per stride
  double stride_amplitude = 0.0;                       // m, fore/aft leg offset amplitude (0 when standing)
  double hip_half_width = 0.1;                         // m, lateral leg offset
  double leg_radius = 0.06;                            // m
};
// Leg centres of a walker (left, right).
std::array<Eigen::Vector2d, 2> legCenters(const WalkerState& w);
void addWalker(Scene& scene, const WalkerState& w, int person_id);
// Advances the gait by the distance walked; amplitude follows speed (0.3 s * v, capped at 0.3 m).
void advanceGait(WalkerState& w, double distance, double dt);

struct LaserModel {
  double angle_min = -3.0 * M_PI / 4.0;
  double angle_increment = M_PI / 540.0;  // 0.333 deg
  std::size_t beams = 811;                // 270 deg
  double range_min = 0.05;
  double range_max = 12.0;
  double noise_sigma = 0.01;     // m, Gaussian range noise
  double dropout_prob = 0.002;   // probability of a missing return on a hit beam
};

struct SimScan {
  LaserScan scan;
  std::vector<int> hit_object;  // per beam, -1 for no return
};

SimScan renderScan(const Scene& scene, const Pose2& sensor, const LaserModel& laser, double stamp,
                   std::mt19937_64& rng);

// Label of a cluster by majority of the objects its beams hit.
struct ClusterLabel {
  bool is_person = false;
  int person = -1;  // person id when is_person
  ObjectClass object_class = ObjectClass::kClutter;
};
ClusterLabel labelCluster(const Cluster& cluster, const SimScan& sim, const Scene& scene);

struct TrainingSceneParams {
  int max_people = 6;
  int max_tables = 3;
  int max_chairs = 6;
  int max_poles = 3;
  int max_clutter = 6;
  double max_distance = 9.0;  // m, objects are placed within this range of the sensor
  // Pedestrians walk in groups (ETH 49 %, hotel 26 %, zara01 70 % of the people walk within 1.2 m of someone at a
  // similar velocity for >= 2 s, from obsmat.txt): each person gets a companion side by side
  // (same heading, 0.45-0.8 m to the left or right) with this probability. 0 draws nothing extra, so the scenes
  // are those of earlier versions. The default AdaBoost model is trained with 0.6 (docs/benchmarks.md "Training on
  // groups": fewer misses on the ETH/UCY bench, no loss in the simulator's furnished worlds).
  double group_probability = 0.0;
};
// A random room around the sensor (at the origin, facing +x): walls with door openings and door leaves,
// furniture, clutter and people (standing or mid-stride). Deterministic in rng.
Scene randomTrainingScene(std::mt19937_64& rng, const TrainingSceneParams& params = {});

}  // namespace cairn::people_tracking
