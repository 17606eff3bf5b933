// Guide tracking (Yuan §2.2.1): one tracked person is the guide the robot follows. States Search (no guide),
// Tracking, Person Lost. The guide is lost when it leaves the field (semicircle of 8 m in front of the robot,
// Yuan §2.2.1) or is not matched by a detection for a timeout. Re-acquisition: an explicit select() command in
// any state (Yuan: the person re-identifies himself and gives a new command), or optionally automatically when
// a confirmed track appears next to the guide's last position within a time window.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "cairn/people_tracking/tracker.hpp"

namespace cairn::people_tracking {

enum class GuideState { kSearch, kTracking, kPersonLost };
const char* toString(GuideState s);

struct GuideParams {
  double field_radius = 8.0;            // m (Yuan §2.2.1: laser semicircle of radius 8 m)
  double field_half_angle = M_PI / 2;   // rad, +-90 deg in front of the robot
  double select_max_distance = 3.0;     // m, select() only considers people this close
  double lost_timeout = 1.0;            // s without a matched detection -> Person Lost
  bool auto_reacquire = true;
  double reacquire_radius = 1.0;        // m around the last guide position
  double reacquire_window = 10.0;       // s; after this the state falls back to Search
};

struct GuideStatus {
  GuideState state = GuideState::kSearch;
  int guide_id = -1;
  std::optional<Track> track;  // the guide's track (tracking frame) while Tracking
  double distance = 0.0;       // polar coordinates in the robot frame (Yuan: angle 0 = straight ahead)
  double bearing = 0.0;
  std::string event;  // "selected", "lost: left field", "lost: timeout", "lost: track deleted", "reacquired", "gave up"
};

class GuideTracker {
 public:
  explicit GuideTracker(GuideParams params = {});

  // Command: make the closest confirmed person in front (inside the field, within select_max_distance) the guide.
  // Returns false when nobody qualifies (state unchanged).
  bool selectClosestInFront(const std::vector<Track>& tracks, const Pose2& robot, double stamp);
  bool selectId(int id, const std::vector<Track>& tracks, double stamp);
  void release();  // back to Search

  GuideStatus update(const std::vector<Track>& tracks, const Pose2& robot, double stamp);
  [[nodiscard]] GuideState state() const { return state_; }
  [[nodiscard]] const GuideParams& params() const { return params_; }
  void setParams(const GuideParams& params) { params_ = params; }  // from the next call on; the state is kept
  [[nodiscard]] int guideId() const { return guide_id_; }

 private:
  bool inField(const Eigen::Vector2d& p, const Pose2& robot) const;
  GuideParams params_;
  GuideState state_ = GuideState::kSearch;
  int guide_id_ = -1;
  Eigen::Vector2d last_position_ = Eigen::Vector2d::Zero();
  double lost_since_ = 0.0;
  std::string pending_event_;
};

}  // namespace cairn::people_tracking
