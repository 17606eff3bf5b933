#include "cairn/sim/world.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

namespace cairn::sim {

// ---------------------------------------------------------------- geometry helpers (types.hpp)
double normalizeAngle(double a) {
  a = std::fmod(a, 2.0 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  if (a > std::numbers::pi) a -= 2.0 * std::numbers::pi;
  return a;
}

Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, normalizeAngle(a.theta + b.theta)};
}

Vec2 transformPoint(const Pose2& pose, Vec2 p) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  return {pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
}

Pose2 between(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, normalizeAngle(b.theta - a.theta)};
}

// ---------------------------------------------------------------- errors
InputError::InputError(std::string file, int line, const std::string& message)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + message),
      file_(std::move(file)),
      line_(line),
      message_(message) {}

// ---------------------------------------------------------------- world elements
bool Region::contains(Vec2 p) const {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Vec2 a = polygon[i], b = polygon[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

Vec2 Region::centroid() const {
  double area2 = 0, cx = 0, cy = 0;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const double c = cross(polygon[j], polygon[i]);
    area2 += c;
    cx += (polygon[j].x + polygon[i].x) * c;
    cy += (polygon[j].y + polygon[i].y) * c;
  }
  if (std::abs(area2) < 1e-12) return polygon.empty() ? Vec2{} : polygon.front();
  return {cx / (3.0 * area2), cy / (3.0 * area2)};
}

std::size_t Schedule::indexAt(double t) const {
  if (times.empty()) return 0;
  if (period > 0.0) {
    t = std::fmod(t, period);
    if (t < 0) t += period;
  }
  // last entry with time <= t; before the first entry: wrap to the last (periodic) or entry 0
  const auto it = std::upper_bound(times.begin(), times.end(), t);
  if (it == times.begin()) return period > 0.0 ? times.size() - 1 : 0;
  return static_cast<std::size_t>(it - times.begin()) - 1;
}

bool Door::isOpen(double t) const { return open.empty() ? initially_open : open[schedule.indexAt(t)]; }

Segment Door::panel(double t) const {
  if (!isOpen(t)) return {hinge, latch, reflectivity};
  const Vec2 d = latch - hinge;
  const double c = std::cos(open_angle), s = std::sin(open_angle);
  return {hinge, {hinge.x + c * d.x - s * d.y, hinge.y + s * d.x + c * d.y}, reflectivity};
}

Pose2 Furniture::poseAt(double t) const {
  if (poses.empty()) return {};
  const std::size_t i = schedule.indexAt(t);
  if (!interpolate || poses.size() < 2) return poses[i];
  const double period = schedule.period;
  double tl = t;
  if (period > 0) {
    tl = std::fmod(t, period);
    if (tl < 0) tl += period;
  }
  double t0 = schedule.times[i], t1 = 0.0;
  std::size_t j = i + 1;
  if (j < poses.size()) {
    t1 = schedule.times[j];
  } else {
    if (period <= 0) return poses[i];  // after the last entry: stay
    j = 0;
    t1 = schedule.times[0] + period;
  }
  if (tl < t0) tl += period;  // before the first entry of a period: moving from the last pose
  const double u = std::clamp((tl - t0) / (t1 - t0), 0.0, 1.0);
  const Pose2& a = poses[i];
  const Pose2& b = poses[j];
  return {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), normalizeAngle(a.theta + u * normalizeAngle(b.theta - a.theta))};
}

void Furniture::geometry(double t, std::vector<Segment>& segments, std::vector<Circle>& circles) const {
  const Pose2 p = poseAt(t);
  const double hl = 0.5 * length, hw = 0.5 * width;
  if (legs_only) {
    const double lx = hl - leg_radius, ly = hw - leg_radius;
    for (const Vec2 c : {Vec2{lx, ly}, Vec2{-lx, ly}, Vec2{-lx, -ly}, Vec2{lx, -ly}})
      circles.push_back({transformPoint(p, c), leg_radius, reflectivity});
    return;
  }
  const Vec2 c[4] = {transformPoint(p, {hl, hw}), transformPoint(p, {-hl, hw}), transformPoint(p, {-hl, -hw}),
                     transformPoint(p, {hl, -hw})};
  for (int i = 0; i < 4; ++i) segments.push_back({c[i], c[(i + 1) % 4], reflectivity});
}

double CrowdConfig::rateAt(double t) const {
  double f = 1.0;
  t += start_time;
  for (const auto& term : terms) f += term.amplitude * std::cos(2.0 * std::numbers::pi * (t - term.phase) / term.period);
  return std::max(0.0, base_rate * f) / 3600.0;
}

const Region* World::region(const std::string& n) const {
  for (const auto& r : regions)
    if (r.name == n) return &r;
  return nullptr;
}

std::string World::regionAt(Vec2 p) const {
  for (const auto& r : regions)
    if (r.contains(p)) return r.name;
  return "";
}

void World::dynamicGeometry(double t, std::vector<Segment>& segments, std::vector<Circle>& circles) const {
  for (const auto& d : doors) segments.push_back(d.panel(t));
  for (const auto& f : furniture) f.geometry(t, segments, circles);
  for (const auto& m : markers) circles.push_back({m.position, m.radius, m.reflectivity});
}

void World::computeBounds() {
  constexpr double inf = std::numeric_limits<double>::infinity();
  bounds_min = {inf, inf};
  bounds_max = {-inf, -inf};
  auto add = [&](Vec2 p) {
    bounds_min = {std::min(bounds_min.x, p.x), std::min(bounds_min.y, p.y)};
    bounds_max = {std::max(bounds_max.x, p.x), std::max(bounds_max.y, p.y)};
  };
  for (const auto& s : walls) {
    add(s.a);
    add(s.b);
  }
  for (const auto& r : regions)
    for (const auto& p : r.polygon) add(p);
  if (bounds_min.x > bounds_max.x) bounds_min = bounds_max = {0, 0};
}

// ---------------------------------------------------------------- YAML parsing
namespace {

constexpr double kMaxCrowdRate = 3600.0;  ///< people per hour per source at the peak (one a second)

struct Parser {
  std::string file;

  [[noreturn]] void fail(const YAML::Node& n, const std::string& msg) const {
    const int line = n.IsDefined() ? n.Mark().line + 1 : 0;
    throw InputError(file, line, msg);
  }

  // Looks up a required key; error names the parent's line and the key path.
  YAML::Node need(const YAML::Node& map, const char* key, const std::string& path) const {
    const YAML::Node n = map[key];
    if (!n) fail(map, "missing key '" + path + key + "'");
    return n;
  }

  void checkKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& path) const {
    if (!map.IsMap()) fail(map, "'" + path + "' must be a mapping");
    std::set<std::string> seen;  // yaml-cpp keeps a repeated key and map[key] finds the first: the second is lost
    for (const auto& kv : map) {
      const auto key = kv.first.as<std::string>();
      if (!allowed.count(key)) fail(kv.first, "unknown key '" + path + key + "'");
      if (!seen.insert(key).second) fail(kv.first, "duplicate key '" + path + key + "'");
    }
  }

  double num(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(n, "'" + path + "' must be a number");
    try {
      const double v = n.as<double>();
      if (!std::isfinite(v)) fail(n, "'" + path + "' must be finite");
      return v;
    } catch (const YAML::Exception&) {
      fail(n, "'" + path + "' must be a number, got '" + n.Scalar() + "'");
    }
  }
  double num(const YAML::Node& map, const char* key, const std::string& path, double def) const {
    const YAML::Node n = map[key];
    return n ? num(n, path + key) : def;
  }
  double positive(const YAML::Node& map, const char* key, const std::string& path, double def) const {
    const YAML::Node n = map[key];
    if (!n) return def;
    const double v = num(n, path + key);
    if (!(v > 0)) fail(n, "'" + path + key + "' must be > 0");
    return v;
  }
  // A number in [lo, hi]; the range is in the message.
  double inRange(const YAML::Node& n, const std::string& path, double lo, double hi) const {
    const double v = num(n, path);
    if (v < lo || v > hi) fail(n, "'" + path + "' must be in " + range(lo, hi) + ", got " + n.Scalar());
    return v;
  }
  double inRange(const YAML::Node& map, const char* key, const std::string& path, double def, double lo, double hi) const {
    const YAML::Node n = map[key];
    return n ? inRange(n, path + key, lo, hi) : def;
  }
  int integer(const YAML::Node& map, const char* key, const std::string& path, int def, int lo, int hi) const {
    const YAML::Node n = map[key];
    if (!n) return def;
    const double v = num(n, path + key);
    if (v != std::floor(v) || v < lo || v > hi)
      fail(n, "'" + path + key + "' must be an integer in " + range(lo, hi) + ", got " + n.Scalar());
    return static_cast<int>(v);
  }
  static std::string range(double lo, double hi) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "[%.15g, %.15g]", lo, hi);
    return buf;
  }
  bool boolean(const YAML::Node& n, const std::string& path) const {
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(n, "'" + path + "' must be true or false");
    }
  }
  std::string str(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(n, "'" + path + "' must be a string");
    return n.Scalar();
  }
  float reflectivity(const YAML::Node& map, const std::string& path, float def) const {
    return static_cast<float>(inRange(map, "reflectivity", path, def, 0.0, 1.0));
  }
  Vec2 point(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence() || n.size() != 2) fail(n, "'" + path + "' must be [x, y]");
    return {num(n[0], path + "[0]"), num(n[1], path + "[1]")};
  }
  Pose2 pose(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence() || (n.size() != 3 && n.size() != 2)) fail(n, "'" + path + "' must be [x, y, theta]");
    return {num(n[0], path + "[0]"), num(n[1], path + "[1]"), n.size() == 3 ? num(n[2], path + "[2]") : 0.0};
  }
  std::vector<Vec2> points(const YAML::Node& n, const std::string& path, std::size_t min_size) const {
    if (!n.IsSequence() || n.size() < min_size)
      fail(n, "'" + path + "' must be a list of at least " + std::to_string(min_size) + " [x, y] points");
    std::vector<Vec2> out;
    for (std::size_t i = 0; i < n.size(); ++i) out.push_back(point(n[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }
  std::string resolve(const std::string& rel) const {
    namespace fs = std::filesystem;
    const fs::path p(rel);
    if (p.is_absolute()) return rel;
    return (fs::path(file).parent_path() / p).lexically_normal().string();
  }
  std::string idx(const std::string& list, std::size_t i) const { return list + "[" + std::to_string(i) + "]."; }

  // schedule: [{t: .., <state_key>: ..}, ...] with times strictly increasing; calls on_entry per entry.
  template <class F>
  void schedule(const YAML::Node& map, const std::string& path, const char* state_key, Schedule& sch, F on_entry) const {
    const YAML::Node s = map["schedule"];
    if (!s) return;
    if (!s.IsSequence() || s.size() == 0) fail(s, "'" + path + "schedule' must be a non-empty list");
    for (std::size_t i = 0; i < s.size(); ++i) {
      const std::string p = path + "schedule[" + std::to_string(i) + "].";
      checkKeys(s[i], {"t", state_key}, p);
      const double t = num(need(s[i], "t", p), p + "t");
      if (!sch.times.empty() && t <= sch.times.back()) fail(s[i], "'" + p + "t' must be increasing");
      sch.times.push_back(t);
      on_entry(need(s[i], state_key, p), p + state_key);
    }
    sch.period = num(map, "period", path, 0.0);
    if (sch.period < 0) fail(map["period"], "'" + path + "period' must be >= 0");
    if (sch.period > 0 && sch.times.back() >= sch.period)
      fail(map["period"], "'" + path + "period' must exceed the last schedule time");
  }

  void map(const YAML::Node& n, World& w, float refl) const {
    YAML::Node m = n;
    std::string mfile = file;
    std::string base = "map.";
    if (n.IsScalar()) {  // path to a ROS map_server YAML
      mfile = resolve(n.Scalar());
      if (std::filesystem::is_directory(mfile)) fail(n, "map file '" + mfile + "' is a directory, not a file");
      try {
        m = YAML::LoadFile(mfile);
      } catch (const YAML::BadFile&) {
        fail(n, "cannot read map file '" + mfile + "'");
      } catch (const YAML::Exception& e) {
        throw InputError(mfile, e.mark.line + 1, e.msg);
      }
      base = "";
    }
    Parser sub{mfile};
    sub.checkKeys(m, {"image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate", "mode"}, base);
    const std::string image = sub.resolve(sub.str(sub.need(m, "image", base), base + "image"));
    const double res = sub.inRange(sub.need(m, "resolution", base), base + "resolution", 0.001, 100.0);  // m per pixel
    const Pose2 origin = sub.pose(sub.need(m, "origin", base), base + "origin");
    const double occ = sub.inRange(m, "occupied_thresh", base, 0.65, 0.0, 1.0);
    sub.inRange(m, "free_thresh", base, 0.196, 0.0, 1.0);  // map_server's; not used here
    const bool negate = sub.integer(m, "negate", base, 0, 0, 1) != 0;
    if (const auto mode = m["mode"]) {
      const std::string v = sub.str(mode, base + "mode");
      if (v != "trinary" && v != "scale" && v != "raw")
        sub.fail(mode, "'" + base + "mode' must be trinary, scale or raw, got '" + v + "'");
    }
    OccupancyImage img;
    try {
      img = readImage(image);
    } catch (const InputError& e) {
      sub.fail(m["image"], "image '" + image + "': " + e.message());
    }
    auto segs = occupancyToSegments(img, res, origin, occ, negate, refl);
    w.walls.insert(w.walls.end(), segs.begin(), segs.end());
  }

  World parse(const YAML::Node& root) const {
    World w;
    w.file = file;
    if (!root.IsMap()) fail(root, "a world file must be a YAML mapping");
    checkKeys(root, {"name", "walls", "segments", "map", "wall_reflectivity", "regions", "doors", "furniture",
                     "markers", "robot", "routes", "people", "crowd"},
              "");
    w.name = root["name"] ? str(root["name"], "name")
                          : std::filesystem::path(file).stem().string();
    const float wall_refl = static_cast<float>(inRange(root, "wall_reflectivity", "", 0.3F, 0.0, 1.0));
    if (const auto n = root["walls"]) {
      if (!n.IsSequence()) fail(n, "'walls' must be a list of polylines");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = "walls[" + std::to_string(i) + "]";
        const auto pts = points(n[i], p, 2);
        for (std::size_t k = 1; k < pts.size(); ++k) w.walls.push_back({pts[k - 1], pts[k], wall_refl});
      }
    }
    if (const auto n = root["segments"]) {
      if (!n.IsSequence()) fail(n, "'segments' must be a list of [x1, y1, x2, y2]");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = "segments[" + std::to_string(i) + "]";
        if (!n[i].IsSequence() || (n[i].size() != 4 && n[i].size() != 5))
          fail(n[i], "'" + p + "' must be [x1, y1, x2, y2] or [x1, y1, x2, y2, reflectivity]");
        Segment s{{num(n[i][0], p), num(n[i][1], p)}, {num(n[i][2], p), num(n[i][3], p)}, wall_refl};
        if (n[i].size() == 5) s.reflectivity = static_cast<float>(inRange(n[i][4], p + "[4]", 0.0, 1.0));
        w.walls.push_back(s);
      }
    }
    if (const auto n = root["map"]) map(n, w, wall_refl);
    if (w.walls.empty()) fail(root, "world has no geometry: give 'walls', 'segments' or 'map'");

    if (const auto n = root["regions"]) {
      if (!n.IsSequence()) fail(n, "'regions' must be a list");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = idx("regions", i);
        checkKeys(n[i], {"name", "polygon", "rect"}, p);
        Region r;
        r.name = str(need(n[i], "name", p), p + "name");
        if (w.region(r.name)) fail(n[i]["name"], "duplicate region name '" + r.name + "'");
        if (const auto rect = n[i]["rect"]) {
          if (!rect.IsSequence() || rect.size() != 4) fail(rect, "'" + p + "rect' must be [xmin, ymin, xmax, ymax]");
          const double x0 = num(rect[0], p + "rect"), y0 = num(rect[1], p + "rect");
          const double x1 = num(rect[2], p + "rect"), y1 = num(rect[3], p + "rect");
          if (!(x1 > x0 && y1 > y0)) fail(rect, "'" + p + "rect' must have xmax > xmin and ymax > ymin");
          r.polygon = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
        } else {
          r.polygon = points(need(n[i], "polygon", p), p + "polygon", 3);
        }
        w.regions.push_back(std::move(r));
      }
    }
    if (const auto n = root["doors"]) {
      if (!n.IsSequence()) fail(n, "'doors' must be a list");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = idx("doors", i);
        checkKeys(n[i], {"name", "hinge", "latch", "open_angle", "open", "schedule", "period", "reflectivity"}, p);
        Door d;
        d.name = n[i]["name"] ? str(n[i]["name"], p + "name") : "door_" + std::to_string(i);
        d.hinge = point(need(n[i], "hinge", p), p + "hinge");
        d.latch = point(need(n[i], "latch", p), p + "latch");
        if (norm(d.latch - d.hinge) < 1e-3) fail(n[i], "'" + p + "latch' must differ from hinge");
        d.open_angle = num(n[i], "open_angle", p, d.open_angle);
        d.reflectivity = reflectivity(n[i], p, wall_refl);
        if (n[i]["open"]) d.initially_open = boolean(n[i]["open"], p + "open");
        schedule(n[i], p, "open", d.schedule,
                 [&](const YAML::Node& v, const std::string& vp) { d.open.push_back(boolean(v, vp)); });
        w.doors.push_back(std::move(d));
      }
    }
    if (const auto n = root["furniture"]) {
      if (!n.IsSequence()) fail(n, "'furniture' must be a list");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = idx("furniture", i);
        checkKeys(n[i], {"name", "size", "legs_only", "leg_radius", "pose", "schedule", "period", "interpolate", "reflectivity"}, p);
        Furniture f;
        f.name = n[i]["name"] ? str(n[i]["name"], p + "name") : "furniture_" + std::to_string(i);
        const Vec2 size = point(need(n[i], "size", p), p + "size");
        if (!(size.x > 0 && size.y > 0)) fail(n[i]["size"], "'" + p + "size' must be positive");
        f.length = size.x;
        f.width = size.y;
        if (n[i]["legs_only"]) f.legs_only = boolean(n[i]["legs_only"], p + "legs_only");
        if (n[i]["interpolate"]) f.interpolate = boolean(n[i]["interpolate"], p + "interpolate");
        f.leg_radius = positive(n[i], "leg_radius", p, f.leg_radius);
        if (2 * f.leg_radius > std::min(f.length, f.width)) fail(n[i]["leg_radius"], "'" + p + "leg_radius' too large");
        f.reflectivity = reflectivity(n[i], p, wall_refl);
        schedule(n[i], p, "pose", f.schedule,
                 [&](const YAML::Node& v, const std::string& vp) { f.poses.push_back(pose(v, vp)); });
        if (f.poses.empty()) f.poses.push_back(pose(need(n[i], "pose", p), p + "pose"));
        else if (n[i]["pose"]) fail(n[i]["pose"], "'" + p + "pose' and '" + p + "schedule' are exclusive");
        w.furniture.push_back(std::move(f));
      }
    }
    if (const auto n = root["markers"]) {
      if (!n.IsSequence()) fail(n, "'markers' must be a list");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = idx("markers", i);
        checkKeys(n[i], {"name", "position", "radius", "reflectivity"}, p);
        Marker m;
        m.name = n[i]["name"] ? str(n[i]["name"], p + "name") : "marker_" + std::to_string(i);
        m.position = point(need(n[i], "position", p), p + "position");
        m.radius = positive(n[i], "radius", p, m.radius);
        m.reflectivity = reflectivity(n[i], p, 1.0F);
        w.markers.push_back(std::move(m));
      }
    }
    if (const auto n = root["robot"]) {
      checkKeys(n, {"start"}, "robot.");
      if (n["start"]) w.robot_start = pose(n["start"], "robot.start");
    }
    if (const auto n = root["routes"]) {
      if (!n.IsMap()) fail(n, "'routes' must be a mapping name -> list of [x, y]");
      for (const auto& kv : n) {
        const auto name = kv.first.as<std::string>();
        w.routes[name] = points(kv.second, "routes." + name, 1);
      }
    }
    if (const auto n = root["people"]) {
      if (!n.IsSequence()) fail(n, "'people' must be a list");
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = idx("people", i);
        checkKeys(n[i], {"kind", "file", "waypoints", "speed", "start_time", "offset", "scale", "time_offset",
                         "frame_period", "loop"},
                  p);
        PeopleSource s;
        s.kind = str(need(n[i], "kind", p), p + "kind");
        if (s.kind == "scripted") {
          s.waypoints = points(need(n[i], "waypoints", p), p + "waypoints", 2);
          s.speed = inRange(n[i], "speed", p, s.speed, 0.01, 10.0);  // m/s; 1e300 never finished a step
          s.start_time = num(n[i], "start_time", p, 0.0);
        } else if (s.kind == "csv" || s.kind == "eth_obsmat" || s.kind == "edinburgh") {
          s.file = resolve(str(need(n[i], "file", p), p + "file"));
          if (!std::filesystem::exists(s.file)) fail(n[i]["file"], "'" + p + "file': no such file '" + s.file + "'");
          if (std::filesystem::is_directory(s.file))
            fail(n[i]["file"], "'" + p + "file': '" + s.file + "' is a directory, not a file");
          if (n[i]["offset"]) s.offset = pose(n[i]["offset"], p + "offset");
          s.scale = positive(n[i], "scale", p, 1.0);
          s.time_offset = num(n[i], "time_offset", p, 0.0);
          s.frame_period = positive(n[i], "frame_period", p, 0.0);
        } else {
          fail(n[i]["kind"], "'" + p + "kind' must be scripted, csv, eth_obsmat or edinburgh, got '" + s.kind + "'");
        }
        if (n[i]["loop"]) s.loop = boolean(n[i]["loop"], p + "loop");
        w.people.push_back(std::move(s));
      }
    }
    if (const auto n = root["crowd"]) {
      const std::string p = "crowd.";
      checkKeys(n, {"sources", "sinks", "base_rate", "terms", "speed", "speed_sigma", "max_people", "start_time"}, p);
      CrowdConfig c;
      auto names = [&](const char* key) {
        const auto list = need(n, key, p);
        if (!list.IsSequence() || list.size() == 0) fail(list, "'" + p + key + "' must be a non-empty list of region names");
        std::vector<std::string> out;
        for (std::size_t i = 0; i < list.size(); ++i) {
          out.push_back(str(list[i], p + key));
          if (!w.region(out.back())) fail(list[i], "'" + p + key + "': unknown region '" + out.back() + "'");
        }
        return out;
      };
      c.sources = names("sources");
      c.sinks = names("sinks");
      // Arrivals are drawn at the peak rate: bounded so that a run cannot drown in candidates (and each
      // draw advances time: at 1e300 per hour it did not, and the run hung).
      c.base_rate = inRange(need(n, "base_rate", p), p + "base_rate", 0.0, kMaxCrowdRate);
      if (const auto t = n["terms"]) {
        if (!t.IsSequence()) fail(t, "'" + p + "terms' must be a list");
        for (std::size_t i = 0; i < t.size(); ++i) {
          const std::string tp = p + "terms[" + std::to_string(i) + "].";
          checkKeys(t[i], {"period", "amplitude", "phase"}, tp);
          CrowdConfig::RateTerm term;
          term.period = positive(t[i], "period", tp, term.period);
          term.amplitude = num(t[i], "amplitude", tp, 0.0);
          term.phase = num(t[i], "phase", tp, 0.0);
          c.terms.push_back(term);
        }
        double peak = 1.0;
        for (const auto& term : c.terms) peak += std::abs(term.amplitude);
        if (c.base_rate * peak > kMaxCrowdRate)
          fail(t, "'" + p + "terms': the peak rate base_rate × (1 + Σ|amplitude|) must be at most " +
                      std::to_string(static_cast<int>(kMaxCrowdRate)) + " people per hour");
      }
      c.speed = inRange(n, "speed", p, c.speed, CrowdConfig::kMinSpeed, CrowdConfig::kMaxSpeed);
      c.speed_sigma = inRange(n, "speed_sigma", p, c.speed_sigma, 0.0, 1.0);
      c.max_people = integer(n, "max_people", p, c.max_people, 0, 1000);
      c.start_time = num(n, "start_time", p, c.start_time);
      w.crowd = c;
    }
    w.computeBounds();
    return w;
  }
};

}  // namespace

World parseWorld(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError(file, e.mark.line + 1, "YAML syntax: " + e.msg);
  }
  try {
    return Parser{file}.parse(root);
  } catch (const YAML::Exception& e) {  // anything the typed accessors did not catch
    throw InputError(file, e.mark.line + 1, e.msg);
  }
}

World loadWorld(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open world file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseWorld(ss.str(), path);
}

}  // namespace cairn::sim
