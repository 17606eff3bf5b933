// Save/load of the whole SLAM state (GraphSlam::save / GraphSlam::load).
//
// File layout (little-endian, version kFileVersion):
//   "CAIRNSLM" | u32 version | u32 section count
//   map options: f64 grid resolution, f64 map resolution
//   nodes:    u64 n, then per node: i64 id, i32 trajectory, f64 stamp, pose local, pose global, i32 submap,
//             points origin, returns, misses, matching points (u64 count + f32 x,y pairs),
//             descriptor (u64 n + f64 scalars, u64 h + per histogram u64 n + f64 values, i32 points, f64 fov)
//   submaps:  u64 n, then per submap: i32 trajectory, pose local, u8 finished, u64 k + i64 node ids
//   edges:    u64 n, then per edge: i64 from, i64 to, u8 kind, pose z, f64[6] information upper triangle, f64 score
//   records:  u64 n, then per scan: f64 stamp, i64 node, pose relative
//   u64 FNV-1a hash of everything before it
// Poses are f64 x, y, theta. Submap grids are not stored: load() rebuilds them by inserting their nodes' scans
// at the nodes' local poses, exactly as local SLAM built them.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "cairn/graph_slam/probability_grid.hpp"
#include "cairn/graph_slam/slam.hpp"
#include "slam_impl.hpp"

namespace cairn::graph_slam {
namespace {

constexpr char kMagic[8] = {'C', 'A', 'I', 'R', 'N', 'S', 'L', 'M'};
constexpr std::uint64_t kMaxCount = 1ULL << 32;  // no section of a sane file has more entries

std::uint64_t fnv1a(const char* data, std::size_t n) {
  std::uint64_t h = 1469598103934665603ULL;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ULL;
  }
  return h;
}

class Writer {
 public:
  template <typename T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    buf_.insert(buf_.end(), p, p + sizeof(T));
  }
  void pose(const Pose2& p) {
    put(p.t.x());
    put(p.t.y());
    put(p.theta);
  }
  void points(const std::vector<Eigen::Vector2d>& pts) {
    put<std::uint64_t>(pts.size());
    for (const auto& p : pts) {
      put(static_cast<float>(p.x()));
      put(static_cast<float>(p.y()));
    }
  }
  void doubles(const std::vector<double>& v) {
    put<std::uint64_t>(v.size());
    for (double x : v) put(x);
  }
  std::vector<char>& bytes() { return buf_; }

 private:
  std::vector<char> buf_;
};

class Reader {
 public:
  Reader(const std::string& path, const std::vector<char>& buf, std::size_t end) : path_(path), buf_(buf), end_(end) {}
  void section(const char* name) { section_ = name; }
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    if (pos_ + sizeof(T) > end_) fail("truncated");
    T v;
    std::memcpy(&v, buf_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::uint64_t count() {
    const auto n = get<std::uint64_t>();
    if (n > kMaxCount) fail("implausible count " + std::to_string(n));
    return n;
  }
  double finite() {
    const double v = get<double>();
    if (!std::isfinite(v)) fail("non-finite number");
    return v;
  }
  Pose2 pose() {
    Pose2 p;
    p.t.x() = finite();
    p.t.y() = finite();
    p.theta = normalizeAngle(finite());
    return p;
  }
  std::vector<Eigen::Vector2d> points() {
    const std::uint64_t n = count();
    if (n * 8 > end_ - pos_) fail("truncated");
    std::vector<Eigen::Vector2d> out(static_cast<std::size_t>(n));
    for (auto& p : out) {
      const float x = get<float>(), y = get<float>();
      if (!std::isfinite(x) || !std::isfinite(y)) fail("non-finite point");
      p = {x, y};
    }
    return out;
  }
  std::vector<double> doubles() {
    const std::uint64_t n = count();
    if (n * 8 > end_ - pos_) fail("truncated");
    std::vector<double> out(static_cast<std::size_t>(n));
    for (double& v : out) v = get<double>();
    return out;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path_ + ": " + what + " at byte " + std::to_string(pos_) + " (reading " + section_ + ")");
  }
  std::size_t pos() const { return pos_; }

 private:
  const std::string& path_;
  const std::vector<char>& buf_;
  std::size_t end_;
  std::size_t pos_ = 0;
  const char* section_ = "header";
};

}  // namespace

void GraphSlam::save(const std::string& path) const {
  const Impl& s = *impl_;
  Writer w;
  for (char c : kMagic) w.put(c);
  w.put<std::uint32_t>(kFileVersion);
  w.put<std::uint32_t>(4);
  w.put(s.options.local.grid_resolution);
  w.put(s.options.map_resolution);
  w.put<std::uint64_t>(s.nodes.size());
  for (const SlamNode& n : s.nodes) {
    w.put<std::int64_t>(n.id);
    w.put<std::int32_t>(n.trajectory);
    w.put(n.stamp);
    w.pose(n.local_pose);
    w.pose(n.global_pose);
    w.put<std::int32_t>(n.submap);
    w.put(n.range_data.origin.x());
    w.put(n.range_data.origin.y());
    w.points(n.range_data.returns);
    w.points(n.range_data.misses);
    w.points(n.matching_points);
    w.doubles(n.descriptor.scalars);
    w.put<std::uint64_t>(n.descriptor.histograms.size());
    for (const auto& h : n.descriptor.histograms) w.doubles(h);
    w.put<std::int32_t>(n.descriptor.points);
    w.put(n.descriptor.fov);
  }
  w.put<std::uint64_t>(s.submaps.size());
  for (const SlamSubmap& m : s.submaps) {
    w.put<std::int32_t>(m.trajectory);
    w.pose(m.local_pose);
    w.put<std::uint8_t>(m.finished ? 1 : 0);
    w.put<std::uint64_t>(m.nodes.size());
    for (std::int64_t id : m.nodes) w.put(id);
  }
  w.put<std::uint64_t>(s.edges.size());
  for (const SlamEdge& e : s.edges) {
    w.put(e.from);
    w.put(e.to);
    w.put<std::uint8_t>(static_cast<std::uint8_t>(e.kind));
    w.pose(e.z);
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) w.put(e.information(r, c));
    w.put(e.score);
  }
  w.put<std::uint64_t>(s.records.size());
  for (const ScanRecord& r : s.records) {
    w.put(r.stamp);
    w.put(r.node);
    w.pose(r.relative);
  }
  const std::uint64_t hash = fnv1a(w.bytes().data(), w.bytes().size());
  w.put(hash);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write file");
    out.write(w.bytes().data(), static_cast<std::streamsize>(w.bytes().size()));
    if (!out) throw std::runtime_error(path + ": error while writing file");
  }
  // Write-then-rename: an interrupted save never leaves a half-written state file under the real name.
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error(path + ": cannot rename " + tmp);
}

GraphSlam GraphSlam::load(const std::string& path, SlamOptions options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open file");
  const std::vector<char> buf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (std::memcmp(buf.data(), kMagic, std::min(buf.size(), sizeof(kMagic))) != 0 || buf.empty())
    throw std::runtime_error(path + ": not a cairn SLAM state file");
  if (buf.size() < sizeof(kMagic) + 8) throw std::runtime_error(path + ": truncated (" + std::to_string(buf.size()) + " bytes)");
  std::uint32_t version = 0;
  std::memcpy(&version, buf.data() + sizeof(kMagic), sizeof(version));
  if (version != kFileVersion)
    throw std::runtime_error(path + ": SLAM state file format version " + std::to_string(version) +
                             ", this build reads version " + std::to_string(kFileVersion));
  if (buf.size() < sizeof(kMagic) + 8 + 8) throw std::runtime_error(path + ": truncated (no checksum)");
  const std::size_t end = buf.size() - 8;
  std::uint64_t stored = 0;
  std::memcpy(&stored, buf.data() + end, 8);
  Reader r(path, buf, end);
  for (std::size_t i = 0; i < sizeof(kMagic) + 4; ++i) r.get<char>();
  if (r.get<std::uint32_t>() != 4) r.fail("unexpected section count");
  if (fnv1a(buf.data(), end) != stored) throw std::runtime_error(path + ": checksum mismatch (truncated or corrupt file)");
  const double grid_resolution = r.finite();
  const double map_resolution = r.finite();
  if (grid_resolution <= 0 || map_resolution <= 0) r.fail("non-positive resolution");
  options.local.grid_resolution = grid_resolution;

  GraphSlam slam(options);
  Impl& s = *slam.impl_;
  r.section("nodes");
  const std::uint64_t n_nodes = r.count();
  s.nodes.reserve(static_cast<std::size_t>(n_nodes));
  int max_trajectory = -1;
  for (std::uint64_t i = 0; i < n_nodes; ++i) {
    SlamNode n;
    n.id = r.get<std::int64_t>();
    if (n.id != static_cast<std::int64_t>(i)) r.fail("node ids must be 0..n-1 in order");
    n.trajectory = r.get<std::int32_t>();
    if (n.trajectory < 0) r.fail("negative trajectory");
    max_trajectory = std::max(max_trajectory, n.trajectory);
    n.stamp = r.finite();
    n.local_pose = r.pose();
    n.global_pose = r.pose();
    n.submap = r.get<std::int32_t>();
    n.range_data.origin.x() = r.finite();
    n.range_data.origin.y() = r.finite();
    n.range_data.returns = r.points();
    n.range_data.misses = r.points();
    n.matching_points = r.points();
    n.descriptor.scalars = r.doubles();
    const std::uint64_t nh = r.count();
    for (std::uint64_t h = 0; h < nh; ++h) n.descriptor.histograms.push_back(r.doubles());
    n.descriptor.points = r.get<std::int32_t>();
    n.descriptor.fov = r.get<double>();
    s.nodes.push_back(std::move(n));
  }
  r.section("submaps");
  const std::uint64_t n_submaps = r.count();
  for (std::uint64_t i = 0; i < n_submaps; ++i) {
    SlamSubmap m;
    m.trajectory = r.get<std::int32_t>();
    m.local_pose = r.pose();
    r.get<std::uint8_t>();
    m.finished = true;  // a loaded submap never grows again
    const std::uint64_t k = r.count();
    auto grid = std::make_shared<Submap>();
    grid->local_pose = m.local_pose;
    grid->grid = ProbabilityGrid(s.options.local.grid_resolution, s.options.local.grid);
    grid->finished = true;
    grid->index = static_cast<int>(i);
    for (std::uint64_t j = 0; j < k; ++j) {
      const auto id = r.get<std::int64_t>();
      if (id < 0 || static_cast<std::uint64_t>(id) >= n_nodes) r.fail("submap refers to unknown node " + std::to_string(id));
      m.nodes.push_back(id);
      const SlamNode& node = s.nodes[static_cast<std::size_t>(id)];
      grid->grid.insert(node.range_data, compose(inverse(m.local_pose), node.local_pose));
      ++grid->num_scans;
    }
    grid->grid.crop();
    m.submap = grid;
    s.submaps.push_back(std::move(m));
  }
  for (const SlamNode& n : s.nodes)
    if (n.submap < -1 || n.submap >= static_cast<int>(n_submaps)) r.fail("node refers to unknown submap");
  r.section("edges");
  const std::uint64_t n_edges = r.count();
  for (const SlamNode& n : s.nodes) s.graph.addPose2(n.id, n.global_pose);
  if (!s.nodes.empty()) s.graph.setFixed(0);
  for (std::uint64_t i = 0; i < n_edges; ++i) {
    SlamEdge e;
    e.from = r.get<std::int64_t>();
    e.to = r.get<std::int64_t>();
    if (e.from < 0 || e.to < 0 || static_cast<std::uint64_t>(e.from) >= n_nodes || static_cast<std::uint64_t>(e.to) >= n_nodes)
      r.fail("edge refers to unknown node");
    const auto kind = r.get<std::uint8_t>();
    if (kind > 2) r.fail("unknown edge kind " + std::to_string(kind));
    e.kind = static_cast<EdgeKind>(kind);
    e.z = r.pose();
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) e.information(a, b) = e.information(b, a) = r.finite();
    e.score = r.get<double>();
    try {
      if (e.kind == EdgeKind::kPrior) {
        s.graph.addPrior2(e.from, e.z, e.information);
      } else {
        const std::size_t f = s.graph.addBetween2(e.from, e.to, e.z, e.information);
        if (e.kind == EdgeKind::kLoop) s.graph.setRobustKernel(f, s.loop_kernel);
      }
    } catch (const std::invalid_argument& ex) {
      r.fail(std::string("bad edge: ") + ex.what());
    }
    s.edges.push_back(e);
  }
  r.section("records");
  const std::uint64_t n_records = r.count();
  for (std::uint64_t i = 0; i < n_records; ++i) {
    ScanRecord rec;
    rec.stamp = r.finite();
    rec.node = r.get<std::int64_t>();
    if (rec.node < 0 || static_cast<std::uint64_t>(rec.node) >= n_nodes) r.fail("scan record refers to unknown node");
    rec.relative = r.pose();
    if (s.options.load_scan_records) s.records.push_back(rec);  // read (and checked) either way
  }
  if (r.pos() != end) r.fail("trailing bytes");
  s.caches.resize(s.submaps.size());
  s.stats.nodes = s.nodes.size();
  s.stats.submaps = s.submaps.size();
  // Continue in a new trajectory (multi-session) or localize: either way the robot's place in the loaded map is
  // unknown until a global search (Stüde §3.2.1) links it.
  s.trajectory = max_trajectory + 1;
  s.startTrajectory();  // trajectory_first_node = all loaded nodes
  s.linked = s.nodes.empty();
  return slam;
}

}  // namespace cairn::graph_slam
