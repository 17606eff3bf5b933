#include "cairn/sim/people.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <queue>
#include <sstream>

namespace cairn::sim {

// ---------------------------------------------------------------- legs
void legPositions(const GaitConfig& g, Vec2 position, double heading, double speed, double phase, Vec2 legs[2]) {
  const Vec2 fwd{std::cos(heading), std::sin(heading)};
  const Vec2 left{-fwd.y, fwd.x};
  const double swing = g.swing_amplitude * std::min(1.0, std::abs(speed) / g.swing_speed) * std::sin(phase);
  legs[0] = position + g.hip_half_width * left + swing * fwd;
  legs[1] = position - g.hip_half_width * left - swing * fwd;
}

// ---------------------------------------------------------------- trajectories
void Trajectory::sample(double time, Vec2& pos, Vec2& vel) const {
  if (t.size() == 1) {
    pos = p.front();
    vel = {};
    return;
  }
  auto it = std::upper_bound(t.begin(), t.end(), time);
  std::size_t i1 = std::clamp<std::size_t>(static_cast<std::size_t>(it - t.begin()), 1, t.size() - 1);
  const std::size_t i0 = i1 - 1;
  const double dt = t[i1] - t[i0];
  const double u = dt > 0 ? std::clamp((time - t[i0]) / dt, 0.0, 1.0) : 0.0;
  pos = p[i0] + u * (p[i1] - p[i0]);
  vel = dt > 0 ? (1.0 / dt) * (p[i1] - p[i0]) : Vec2{};
}

namespace {
bool parseDouble(const std::string& s, double& out) {
  const char* b = s.c_str();
  char* e = nullptr;
  out = std::strtod(b, &e);
  if (e == b) return false;
  while (*e == ' ' || *e == '\t' || *e == '\r') ++e;
  return *e == '\0' && std::isfinite(out);
}

std::vector<Trajectory> group(std::map<int, Trajectory>& by_id) {
  std::vector<Trajectory> out;
  for (auto& [id, tr] : by_id) {
    std::vector<std::size_t> order(tr.t.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return tr.t[a] < tr.t[b]; });
    Trajectory s;
    s.id = id;
    for (auto i : order) s.t.push_back(tr.t[i]), s.p.push_back(tr.p[i]);
    out.push_back(std::move(s));
  }
  return out;
}

std::ifstream openOrThrow(const std::string& path) {
  // a directory opens as a stream that reads nothing: it would pass as a file without trajectories
  if (std::filesystem::is_directory(path)) throw InputError(path, 0, "is a directory, not a file");
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open file");
  return in;
}
}  // namespace

std::vector<Trajectory> loadTrajectoriesCsv(const std::string& path) {
  auto in = openOrThrow(path);
  std::map<int, Trajectory> by_id;
  std::string line;
  int lineno = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string item;
    while (std::getline(ss, item, ',')) f.push_back(item);
    double v[4];
    bool ok = f.size() == 4;
    for (int i = 0; ok && i < 4; ++i) ok = parseDouble(f[i], v[i]);
    if (!ok) {
      if (first) {  // header line
        first = false;
        continue;
      }
      throw InputError(path, lineno, "expected 't,id,x,y' with numbers, got '" + line + "'");
    }
    first = false;
    if (v[1] != std::floor(v[1])) throw InputError(path, lineno, "id must be an integer");
    Trajectory& tr = by_id[static_cast<int>(v[1])];
    tr.t.push_back(v[0]);
    tr.p.push_back({v[2], v[3]});
  }
  return group(by_id);
}

std::vector<Trajectory> loadEthObsmat(const std::string& path, double frame_period) {
  auto in = openOrThrow(path);
  std::map<int, Trajectory> by_id;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::stringstream ss(line);
    double v[8];
    int n = 0;
    while (n < 8 && ss >> v[n]) ++n;
    if (n == 0 && line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::string rest;
    if (n != 8 || (ss >> rest)) throw InputError(path, lineno, "expected 8 numbers (frame ped_id x z y vx vz vy)");
    Trajectory& tr = by_id[static_cast<int>(v[1])];
    tr.t.push_back(v[0] * frame_period);
    tr.p.push_back({v[2], v[4]});
  }
  return group(by_id);
}

std::vector<Trajectory> loadEdinburghTracks(const std::string& path, double frame_period, double mpp) {
  auto in = openOrThrow(path);
  std::map<int, Trajectory> by_id;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto pos = line.find("TRACK.R");
    if (pos == std::string::npos) continue;
    const auto eq = line.find('=', pos);
    if (eq == std::string::npos) throw InputError(path, lineno, "TRACK entry without '='");
    int id = 0;
    try {
      id = std::stoi(line.substr(pos + 7, eq - pos - 7));
    } catch (const std::exception&) {
      throw InputError(path, lineno, "bad TRACK id");
    }
    // [[x y t];[x y t];...] with an optional ';' at the end; anything else (a cut-off line) is an error
    const std::string name = "TRACK.R" + std::to_string(id);
    const char* c = line.c_str() + eq + 1;
    auto skip = [&] {
      while (*c == ' ' || *c == '\t' || *c == '\r') ++c;
    };
    auto expect = [&](char want, const char* what) {
      skip();
      if (*c != want) throw InputError(path, lineno, name + ": " + what + (*c ? "" : " (line cut off?)"));
      ++c;
    };
    std::vector<double> nums;
    expect('[', "expected '[[x y t];...]'");
    for (;;) {
      expect('[', "expected '[x y t]'");
      for (int k = 0; k < 3; ++k) {
        skip();
        char* e = nullptr;
        const double v = std::strtod(c, &e);
        if (e == c || !std::isfinite(v)) throw InputError(path, lineno, "non-numeric value in " + name);
        nums.push_back(v);
        c = e;
      }
      expect(']', "TRACK entries must be [x y t] triples");
      skip();
      if (*c == ';') {
        ++c;
        continue;
      }
      expect(']', "expected ';' or ']' after [x y t]");
      break;
    }
    skip();
    if (*c == ';') ++c;
    skip();
    if (*c) throw InputError(path, lineno, name + ": unexpected text after the track");
    Trajectory& tr = by_id[id];
    for (std::size_t i = 0; i < nums.size(); i += 3) {
      tr.p.push_back({nums[i] * mpp, nums[i + 1] * mpp});
      tr.t.push_back(nums[i + 2] * frame_period);
    }
  }
  return group(by_id);
}

std::vector<Trajectory> loadPeopleSource(const PeopleSource& src) {
  std::vector<Trajectory> trajs;
  const char* expected = "";
  if (src.kind == "csv") {
    trajs = loadTrajectoriesCsv(src.file);
    expected = "t,id,x,y lines";
  } else if (src.kind == "eth_obsmat") {
    trajs = src.frame_period > 0 ? loadEthObsmat(src.file, src.frame_period) : loadEthObsmat(src.file);
    expected = "ETH/UCY obsmat lines";
  } else if (src.kind == "edinburgh") {
    trajs = src.frame_period > 0 ? loadEdinburghTracks(src.file, src.frame_period) : loadEdinburghTracks(src.file);
    expected = "Edinburgh TRACK.R<id>=[[x y t];...] lines";
  } else {
    throw InputError(src.file, 0, "unknown people source kind '" + src.kind + "'");
  }
  if (trajs.empty()) throw InputError(src.file, 0, "no trajectories (kind " + src.kind + ": expected " + expected + ")");
  transformTrajectories(trajs, src.offset, src.scale, src.time_offset);
  return trajs;
}

void transformTrajectories(std::vector<Trajectory>& trajs, const Pose2& offset, double scale, double time_offset) {
  for (auto& tr : trajs) {
    for (auto& p : tr.p) p = transformPoint(offset, scale * p);
    for (auto& t : tr.t) t += time_offset;
  }
}

// ---------------------------------------------------------------- free space + A*
namespace {
double pointSegDist(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 e = b - a;
  const double l2 = dot(e, e);
  const double u = l2 > 0 ? std::clamp(dot(p - a, e) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + u * e));
}
}  // namespace

FreeSpaceGrid::FreeSpaceGrid(const World& world, double resolution, double clearance) : res_(resolution) {
  min_ = {world.bounds_min.x - clearance, world.bounds_min.y - clearance};
  const double w = world.bounds_max.x - world.bounds_min.x, h = world.bounds_max.y - world.bounds_min.y;
  const double fx = std::ceil((w + 2 * clearance) / res_) + 1, fy = std::ceil((h + 2 * clearance) / res_) + 1;
  constexpr double kMaxCells = 25e6;  // about 1 km x 1 km at 0.2 m; A* allocates ~14 bytes per cell per plan
  if (!(fx * fy <= kMaxCells)) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "crowd: the world's extent of %.6g x %.6g m is too large for the crowd's free-space grid "
                  "(%.3g cells of %g m, at most %.0f)", w, h, fx * fy, res_, kMaxCells);
    throw InputError(world.file, 0, msg);
  }
  nx_ = static_cast<int>(fx);
  ny_ = static_cast<int>(fy);
  blocked_.assign(static_cast<std::size_t>(nx_) * ny_, 0);
  std::vector<Segment> segs = world.walls;
  std::vector<Circle> circles;
  for (const auto& f : world.furniture)
    if (f.schedule.times.empty()) f.geometry(0.0, segs, circles);  // static furniture only
  auto mark = [&](double x0, double y0, double x1, double y1, auto&& dist) {
    const int cx0 = std::max(0, static_cast<int>((x0 - clearance - min_.x) / res_));
    const int cx1 = std::min(nx_ - 1, static_cast<int>((x1 + clearance - min_.x) / res_) + 1);
    const int cy0 = std::max(0, static_cast<int>((y0 - clearance - min_.y) / res_));
    const int cy1 = std::min(ny_ - 1, static_cast<int>((y1 + clearance - min_.y) / res_) + 1);
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const Vec2 c{min_.x + (cx + 0.5) * res_, min_.y + (cy + 0.5) * res_};
        if (dist(c) < clearance) blocked_[index(cx, cy)] = 1;
      }
  };
  for (const auto& s : segs)
    mark(std::min(s.a.x, s.b.x), std::min(s.a.y, s.b.y), std::max(s.a.x, s.b.x), std::max(s.a.y, s.b.y),
         [&](Vec2 c) { return pointSegDist(c, s.a, s.b); });
  for (const auto& c : circles)
    mark(c.center.x - c.radius, c.center.y - c.radius, c.center.x + c.radius, c.center.y + c.radius,
         [&](Vec2 p) { return norm(p - c.center) - c.radius; });
  // Closed door panels: cells near the panel (not already blocked) are blocked while the door is closed.
  door_of_cell_.assign(blocked_.size(), -1);
  door_closed_.assign(world.doors.size(), false);
  const double door_clearance = std::max(res_, 0.1);
  for (std::size_t d = 0; d < world.doors.size(); ++d) {
    const Vec2 a = world.doors[d].hinge, b = world.doors[d].latch;
    const int cx0 = std::max(0, static_cast<int>((std::min(a.x, b.x) - door_clearance - min_.x) / res_));
    const int cx1 = std::min(nx_ - 1, static_cast<int>((std::max(a.x, b.x) + door_clearance - min_.x) / res_) + 1);
    const int cy0 = std::max(0, static_cast<int>((std::min(a.y, b.y) - door_clearance - min_.y) / res_));
    const int cy1 = std::min(ny_ - 1, static_cast<int>((std::max(a.y, b.y) + door_clearance - min_.y) / res_) + 1);
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const Vec2 c{min_.x + (cx + 0.5) * res_, min_.y + (cy + 0.5) * res_};
        if (!blocked_[index(cx, cy)] && pointSegDist(c, a, b) < door_clearance) door_of_cell_[index(cx, cy)] = static_cast<int>(d);
      }
  }
}

void FreeSpaceGrid::setDoorTime(const World& world, double t) {
  for (std::size_t d = 0; d < world.doors.size() && d < door_closed_.size(); ++d) door_closed_[d] = !world.doors[d].isOpen(t);
}

bool FreeSpaceGrid::free(Vec2 p) const {
  return cellFree(static_cast<int>(std::floor((p.x - min_.x) / res_)), static_cast<int>(std::floor((p.y - min_.y) / res_)));
}

bool FreeSpaceGrid::lineFree(Vec2 a, Vec2 b) const {
  const double len = norm(b - a);
  const int n = std::max(1, static_cast<int>(std::ceil(len / (0.5 * res_))));
  for (int i = 0; i <= n; ++i)
    if (!free(a + (static_cast<double>(i) / n) * (b - a))) return false;
  return true;
}

std::vector<Vec2> FreeSpaceGrid::plan(Vec2 a, Vec2 b) const {
  const int sx = static_cast<int>(std::floor((a.x - min_.x) / res_)), sy = static_cast<int>(std::floor((a.y - min_.y) / res_));
  const int gx = static_cast<int>(std::floor((b.x - min_.x) / res_)), gy = static_cast<int>(std::floor((b.y - min_.y) / res_));
  if (!cellFree(sx, sy) || !cellFree(gx, gy)) return {};
  const std::size_t n = blocked_.size();
  std::vector<double> g(n, std::numeric_limits<double>::infinity());
  std::vector<int> parent(n, -1);
  std::vector<std::uint8_t> closed(n, 0);
  auto h = [&](int cx, int cy) {  // octile distance
    const double dx = std::abs(cx - gx), dy = std::abs(cy - gy);
    return (dx + dy) + (std::numbers::sqrt2 - 2.0) * std::min(dx, dy);
  };
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  const int start = index(sx, sy), goal = index(gx, gy);
  g[start] = 0;
  open.push({h(sx, sy), start});
  while (!open.empty()) {
    const int cur = open.top().second;
    open.pop();
    if (closed[cur]) continue;
    closed[cur] = 1;
    if (cur == goal) break;
    const int cx = cur % nx_, cy = cur / nx_;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int nx = cx + dx, ny = cy + dy;
        if (!cellFree(nx, ny)) continue;
        if (dx && dy && (!cellFree(cx + dx, cy) || !cellFree(cx, cy + dy))) continue;  // no corner cutting
        const int ni = index(nx, ny);
        const double ng = g[cur] + ((dx && dy) ? std::numbers::sqrt2 : 1.0);
        if (ng < g[ni]) {
          g[ni] = ng;
          parent[ni] = cur;
          open.push({ng + h(nx, ny), ni});
        }
      }
  }
  if (!closed[goal]) return {};
  std::vector<Vec2> cells;
  for (int c = goal; c != -1; c = parent[c])
    cells.push_back({min_.x + (c % nx_ + 0.5) * res_, min_.y + (c / nx_ + 0.5) * res_});
  std::reverse(cells.begin(), cells.end());
  cells.front() = a;
  cells.back() = b;
  // line-of-sight shortcutting
  std::vector<Vec2> path{cells.front()};
  std::size_t i = 0;
  while (i + 1 < cells.size()) {
    std::size_t j = cells.size() - 1;
    while (j > i + 1 && !lineFree(cells[i], cells[j])) --j;
    path.push_back(cells[j]);
    i = j;
  }
  return path;
}

bool FreeSpaceGrid::samplePoint(const Region& region, Rng& rng, Vec2& out) const {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& p : region.polygon) x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  for (int k = 0; k < 200; ++k) {
    const Vec2 p{rng.uniform(x0, x1), rng.uniform(y0, y1)};
    if (region.contains(p) && free(p)) {
      out = p;
      return true;
    }
  }
  return false;
}

// ---------------------------------------------------------------- people simulator
PeopleSimulator::PeopleSimulator(const World& world, GaitConfig gait, Rng rng, bool enable_sources, bool enable_crowd)
    : world_(world), gait_(gait), rng_(rng), crowd_(enable_crowd && world.crowd.has_value()) {
  for (const auto& src : world.people) {
    if (!enable_sources) break;
    if (src.kind == "scripted") {
      addScripted(src.waypoints, src.speed, src.start_time);
      continue;
    }
    addTrajectories(loadPeopleSource(src), src.loop);
  }
  if (crowd_) free_ = std::make_unique<FreeSpaceGrid>(world);
}

void PeopleSimulator::addTrajectories(std::vector<Trajectory> trajs, bool loop) {
  if (trajs.empty()) return;
  double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
  for (const auto& tr : trajs) t0 = std::min(t0, tr.start()), t1 = std::max(t1, tr.end());
  for (auto& tr : trajs) {
    trajectories_.push_back(std::make_unique<Trajectory>(std::move(tr)));
    Agent a;
    a.id = next_id_++;
    a.kind = Agent::Kind::Recorded;
    a.traj = trajectories_.back().get();
    a.loop = loop;
    a.start_time = t0;          // loop window start
    a.speed = t1 - t0 + 1.0;    // loop period (reused field)
    agents_.push_back(std::move(a));
  }
}

void PeopleSimulator::addScripted(std::vector<Vec2> waypoints, double speed, double start_time) {
  Agent a;
  a.id = next_id_++;
  a.kind = Agent::Kind::Scripted;
  a.path = std::move(waypoints);
  a.speed = speed;
  a.start_time = start_time;
  a.pos = a.path.front();
  a.heading = std::atan2(a.path[1].y - a.path[0].y, a.path[1].x - a.path[0].x);
  agents_.push_back(std::move(a));
}

void PeopleSimulator::moveAlongPath(Agent& a, double dt) {
  double remaining = a.speed * dt;
  while (remaining > 0 && !a.done) {
    if (a.next >= a.path.size()) {
      if (a.kind == Agent::Kind::Scripted) a.next = 0;  // scripted walkers loop
      else {
        a.done = true;
        break;
      }
    }
    const Vec2 target = a.path[a.next];
    const Vec2 d = target - a.pos;
    const double dist = norm(d);
    if (dist > 1e-9) a.heading = std::atan2(d.y, d.x);
    if (dist <= remaining) {
      a.pos = target;
      remaining -= dist;
      ++a.next;
    } else {
      a.pos = a.pos + (remaining / dist) * d;
      remaining = 0;
    }
  }
}

void PeopleSimulator::spawnCrowd(double t0, double t1) {
  // Non-homogeneous Poisson arrivals per source by thinning (Lewis & Shedler 1979): candidates at the
  // peak rate, accepted with rate(t)/peak. The stream does not depend on the update step.
  const CrowdConfig& c = *world_.crowd;
  double peak_factor = 1.0;
  for (const auto& term : c.terms) peak_factor += std::abs(term.amplitude);
  const double peak = c.base_rate * peak_factor / 3600.0;
  if (peak <= 0) return;
  if (!started_) {
    next_arrival_.assign(c.sources.size(), 0.0);
    for (auto& na : next_arrival_) na = t0 - std::log(1.0 - rng_.uniform()) / peak;
  }
  for (std::size_t s = 0; s < c.sources.size(); ++s) {
    while (next_arrival_[s] <= t1) {
      const double t = next_arrival_[s];
      next_arrival_[s] = t - std::log(1.0 - rng_.uniform()) / peak;
      const double accept = rng_.uniform();
      const std::size_t sink_idx = static_cast<std::size_t>(rng_.uniform() * c.sinks.size());
      const double speed = std::clamp(rng_.gaussian(c.speed, c.speed_sigma), CrowdConfig::kMinSpeed, CrowdConfig::kMaxSpeed);
      if (accept * peak > c.rateAt(t)) continue;
      int active = 0;
      for (const auto& a : agents_) active += a.kind == Agent::Kind::Crowd && !a.done;
      if (active >= c.max_people) continue;
      const Region* from = world_.region(c.sources[s]);
      const Region* to = world_.region(c.sinks[sink_idx]);
      Vec2 p0, p1;
      if (!free_->samplePoint(*from, rng_, p0) || !free_->samplePoint(*to, rng_, p1)) continue;
      free_->setDoorTime(world_, t);  // people do not plan through doors that are closed when they start
      auto path = free_->plan(p0, p1);
      if (path.size() < 2) continue;
      Agent a;
      a.id = next_id_++;
      a.kind = Agent::Kind::Crowd;
      a.path = std::move(path);
      a.speed = speed;
      a.start_time = t;
      a.pos = a.path.front();
      a.active = true;
      a.heading = std::atan2(a.path[1].y - a.path[0].y, a.path[1].x - a.path[0].x);
      a.vel = a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
      // walk the part of the step after the arrival time (with the social force: update()'s sub-steps do)
      if (!social_.enabled) moveAlongPath(a, std::max(0.0, t1 - t));
      agents_.push_back(std::move(a));
      ++spawned_;
    }
  }
}

bool PeopleSimulator::followsPath(const Agent& a, double t) const {
  if (a.kind == Agent::Kind::Scripted) return a.active;
  return a.kind == Agent::Kind::Crowd && !a.done && t > a.start_time;
}

void PeopleSimulator::socialStep(double t, double h) {
  // Helbing & Molnár 1995 eq. (1)-(4) with the exponential repulsion of Helbing, Farkas & Vicsek 2000 (see
  // SocialForceConfig). Forces from the positions at the start of the step: the result does not depend on the
  // agents' order.
  const SocialForceConfig& c = social_;
  const double r2max = c.interaction_radius * c.interaction_radius;
  std::vector<Vec2> acc(agents_.size());
  std::vector<char> social(agents_.size(), 0);
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    Agent& a = agents_[i];
    if (!followsPath(a, t)) continue;
    if (a.next >= a.path.size()) a.next = 0;  // scripted walkers loop (crowd agents are done before this)
    const Vec2 to = a.path[a.next] - a.pos;
    const double dist = norm(to);
    const Vec2 e = dist > 1e-9 ? (1.0 / dist) * to : Vec2{std::cos(a.heading), std::sin(a.heading)};
    Vec2 f = (1.0 / c.tau) * (a.speed * e - a.vel);
    bool near = false;
    const auto repel = [&](Vec2 other, Vec2 other_vel, double radius) {
      const Vec2 dp = a.pos - other;
      if (dot(dp, dp) >= r2max) return;
      near = true;
      // Collision prediction (Zanlungo, Ikeda & Kanda 2011): the repulsion acts at the relative position of
      // closest approach within prediction_horizon, so walkers on a collision course turn away early.
      const Vec2 dv = a.vel - other_vel;
      const double vv = dot(dv, dv);
      const double tc = vv > 1e-12 ? std::clamp(-dot(dp, dv) / vv, 0.0, c.prediction_horizon) : 0.0;
      const Vec2 d = dp + tc * dv;
      const double dn = norm(d);
      const Vec2 n = dn > 1e-9 ? (1.0 / dn) * d : Vec2{e.y, -e.x};  // dead ahead: to the right
      const double cos_phi = -dot(n, e);  // 1: the other is straight ahead
      const double w = c.anisotropy + (1.0 - c.anisotropy) * 0.5 * (1.0 + cos_phi);
      const double mag = c.strength * std::exp((c.body_radius + radius - dn) / c.range);
      f = f + (w * mag) * n;
      if (cos_phi > 0) f = f + (c.keep_right * w * mag * cos_phi) * Vec2{e.y, -e.x};
    };
    for (std::size_t j = 0; j < agents_.size(); ++j) {
      const Agent& b = agents_[j];
      const bool present = b.kind == Agent::Kind::Recorded ? b.active : followsPath(b, t);
      if (j != i && present) repel(b.pos, b.vel, c.body_radius);
    }
    if (robot_radius_ > 0) repel(robot_pos_, Vec2{}, robot_radius_);
    acc[i] = f;
    social[i] = near;
  }
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    Agent& a = agents_[i];
    if (!followsPath(a, t)) continue;
    if (!social[i]) {  // nobody within interaction_radius: exactly along the path at the desired speed
      moveAlongPath(a, std::min(h, t - a.start_time));
      a.vel = a.done ? Vec2{} : a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
      continue;
    }
    a.vel = a.vel + h * acc[i];
    const double vmax = c.max_speed_factor * a.speed, v = norm(a.vel);
    if (v > vmax) a.vel = (vmax / v) * a.vel;
    Vec2 p = a.pos + h * a.vel;
    if (free_ && free_->free(a.pos) && !free_->free(p)) {  // slide along walls, never into them
      if (free_->free({p.x, a.pos.y})) p.y = a.pos.y, a.vel.y = 0;
      else if (free_->free({a.pos.x, p.y})) p.x = a.pos.x, a.vel.x = 0;
      else p = a.pos, a.vel = {};
    }
    a.pos = p;
    if (norm(a.vel) > 0.05) a.heading = std::atan2(a.vel.y, a.vel.x);
    while (norm(a.path[a.next] - a.pos) < c.waypoint_tolerance) {
      if (++a.next < a.path.size()) continue;
      if (a.kind == Agent::Kind::Crowd) {
        a.done = true;
        break;
      }
      a.next = 0;
      break;
    }
  }
}

void PeopleSimulator::update(double t) {
  const double dt = started_ ? std::max(0.0, t - t_) : 0.0;
  const double t_prev = started_ ? t_ : t;
  if (crowd_) spawnCrowd(t_prev, t);
  started_ = true;
  if (social_.enabled && dt > 0) {
    // Sub-steps only when two walkers (or a walker and the robot) can come within interaction_radius during
    // this update; otherwise everybody follows the path exactly in one step (same result, much cheaper for
    // long people-only runs).
    double vmax = 0.0;
    std::vector<std::size_t> near;
    for (std::size_t i = 0; i < agents_.size(); ++i) {
      const Agent& a = agents_[i];
      if (followsPath(a, t) || (a.kind == Agent::Kind::Recorded && a.active)) {
        near.push_back(i);
        vmax = std::max(vmax, a.kind == Agent::Kind::Recorded ? norm(a.vel) : social_.max_speed_factor * a.speed);
      }
    }
    const double reach = social_.interaction_radius + 2.0 * vmax * dt;
    bool interact = false;
    for (std::size_t u = 0; u < near.size() && !interact; ++u) {
      const Vec2 p = agents_[near[u]].pos;
      if (robot_radius_ > 0 && norm(p - robot_pos_) < reach) interact = true;
      for (std::size_t v = u + 1; v < near.size() && !interact; ++v) interact = norm(p - agents_[near[v]].pos) < reach;
    }
    const bool recorded_near = std::any_of(near.begin(), near.end(), [&](std::size_t i) { return agents_[i].kind == Agent::Kind::Recorded; });
    if (interact || recorded_near) {
      const int n = std::max(1, static_cast<int>(std::ceil(dt / social_.max_step - 1e-9)));
      for (int k = 1; k <= n; ++k) socialStep(t_prev + dt * k / n, dt / n);
    } else {
      for (auto& a : agents_) {
        if (!followsPath(a, t)) continue;
        moveAlongPath(a, std::min(dt, t - a.start_time));
        a.vel = a.done ? Vec2{} : a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
      }
    }
  }
  t_ = t;
  people_.clear();
  for (auto& a : agents_) {
    Vec2 vel{};
    const Vec2 before = a.pos;
    if (a.kind == Agent::Kind::Recorded) {
      double tt = t;
      if (a.loop) tt = a.start_time + std::fmod(t - a.start_time, a.speed);
      a.active = tt >= a.traj->start() && tt <= a.traj->end();
      if (!a.active) continue;
      a.traj->sample(tt, a.pos, vel);
      a.vel = vel;
      if (norm(vel) > 0.05) a.heading = std::atan2(vel.y, vel.x);
    } else if (a.kind == Agent::Kind::Scripted) {
      if (t < a.start_time) continue;
      if (!a.active) {
        a.active = true;
        a.vel = a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
      } else if (!social_.enabled) {
        moveAlongPath(a, dt);
      }
      vel = social_.enabled ? a.vel : a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
    } else {
      if (a.done) continue;
      if (!social_.enabled && t > a.start_time) moveAlongPath(a, std::min(dt, t - a.start_time));
      if (a.done) continue;
      vel = social_.enabled ? a.vel : a.speed * Vec2{std::cos(a.heading), std::sin(a.heading)};
    }
    const double moved = norm(a.pos - before);
    if (moved < 1.0) a.phase = std::fmod(a.phase + 2.0 * std::numbers::pi * moved / gait_.stride_length, 2.0 * std::numbers::pi);
    PersonState s;
    s.id = a.id;
    s.position = a.pos;
    s.heading = a.heading;
    s.velocity = vel;
    s.leg_radius = gait_.leg_radius;
    legPositions(gait_, a.pos, a.heading, norm(vel), a.phase, s.legs);
    people_.push_back(s);
  }
  // finished crowd agents are dropped so long runs keep constant memory
  std::erase_if(agents_, [](const Agent& a) { return a.kind == Agent::Kind::Crowd && a.done; });
}

void PeopleSimulator::legCircles(std::vector<Circle>& out) const {
  for (const auto& p : people_)
    for (const auto& l : p.legs) out.push_back({l, p.leg_radius, 0.3F});
}

}  // namespace cairn::sim
