#include "cairn/people_tracking/guide.hpp"

#include <cmath>

namespace cairn::people_tracking {

const char* toString(GuideState s) {
  switch (s) {
    case GuideState::kSearch: return "search";
    case GuideState::kTracking: return "tracking";
    case GuideState::kPersonLost: return "person_lost";
  }
  return "?";
}

GuideTracker::GuideTracker(GuideParams params) : params_(params) {}

bool GuideTracker::inField(const Eigen::Vector2d& p, const Pose2& robot) const {
  const Eigen::Vector2d local = robot.inverseTransform(p);
  return local.norm() <= params_.field_radius && std::abs(std::atan2(local.y(), local.x())) <= params_.field_half_angle;
}

bool GuideTracker::selectClosestInFront(const std::vector<Track>& tracks, const Pose2& robot, double stamp) {
  const Track* best = nullptr;
  double best_d = params_.select_max_distance;
  for (const auto& t : tracks) {
    if (!t.confirmed || !inField(t.position(), robot)) continue;
    const double d = robot.inverseTransform(t.position()).norm();
    if (d <= best_d) best = &t, best_d = d;
  }
  if (!best) return false;
  return selectId(best->id, tracks, stamp);
}

bool GuideTracker::selectId(int id, const std::vector<Track>& tracks, double /*stamp*/) {
  for (const auto& t : tracks)
    if (t.id == id && t.confirmed) {
      guide_id_ = id;
      state_ = GuideState::kTracking;
      last_position_ = t.position();
      pending_event_ = "selected";
      return true;
    }
  return false;
}

void GuideTracker::release() {
  state_ = GuideState::kSearch;
  guide_id_ = -1;
}

GuideStatus GuideTracker::update(const std::vector<Track>& tracks, const Pose2& robot, double stamp) {
  GuideStatus out;
  out.event = pending_event_;
  pending_event_.clear();
  auto find = [&](int id) -> const Track* {
    for (const auto& t : tracks)
      if (t.id == id) return &t;
    return nullptr;
  };
  auto lose = [&](const std::string& why) {
    state_ = GuideState::kPersonLost;
    lost_since_ = stamp;
    out.event = "lost: " + why;
  };
  if (state_ == GuideState::kTracking) {
    const Track* t = find(guide_id_);
    if (!t) lose("track deleted");
    else if (stamp - t->last_update > params_.lost_timeout) lose("timeout");
    else if (!inField(t->position(), robot)) lose("left field");
    else last_position_ = t->position();
  } else if (state_ == GuideState::kPersonLost) {
    const Track* same = find(guide_id_);
    const Track* cand = nullptr;
    if (same && same->confirmed && stamp - same->last_update <= params_.lost_timeout && inField(same->position(), robot)) {
      cand = same;  // the guide's own track came back into the field
    } else if (params_.auto_reacquire) {
      double best = params_.reacquire_radius;
      for (const auto& t : tracks) {
        if (!t.confirmed || t.last_update < lost_since_ || !inField(t.position(), robot)) continue;
        const double d = (t.position() - last_position_).norm();
        if (d <= best) best = d, cand = &t;
      }
    }
    if (cand) {
      guide_id_ = cand->id;
      state_ = GuideState::kTracking;
      last_position_ = cand->position();
      out.event = "reacquired";
    } else if (stamp - lost_since_ > params_.reacquire_window) {
      state_ = GuideState::kSearch;
      guide_id_ = -1;
      out.event = "gave up";
    }
  }
  out.state = state_;
  out.guide_id = guide_id_;
  if (state_ == GuideState::kTracking) {
    const Track* t = find(guide_id_);
    out.track = *t;
    const Eigen::Vector2d local = robot.inverseTransform(t->position());
    out.distance = local.norm();
    out.bearing = std::atan2(local.y(), local.x());
  }
  return out;
}

}  // namespace cairn::people_tracking
