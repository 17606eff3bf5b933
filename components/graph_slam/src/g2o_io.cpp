#include "cairn/graph_slam/g2o_io.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <ostream>
#include <set>
#include <string_view>

namespace cairn::graph_slam {

G2oError::G2oError(std::string file, std::size_t line, const std::string& what)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + what),
      file_(std::move(file)),
      line_(line),
      message_(what) {}

namespace {

// Text of the file quoted in a message: at most 40 characters, so that a huge garbage token does not make a
// huge error line.
std::string excerpt(std::string_view s) {
  constexpr std::size_t kMax = 40;
  if (s.size() <= kMax) return std::string(s);
  return std::string(s.substr(0, kMax)) + "... (" + std::to_string(s.size()) + " bytes)";
}

struct Line {
  const std::string* file;
  std::size_t number;
  std::vector<std::string_view> tok;

  [[noreturn]] void fail(const std::string& what) const { throw G2oError(*file, number, what); }

  void expectFields(std::size_t n) const {
    if (tok.size() < n) {
      fail(excerpt(tok[0]) + " needs " + std::to_string(n - 1) + " fields, got " +
           std::to_string(tok.size() - 1) + " (truncated line?)");
    }
    if (tok.size() > n) {
      fail(excerpt(tok[0]) + " needs " + std::to_string(n - 1) + " fields, got " +
           std::to_string(tok.size() - 1));
    }
  }

  double number_at(std::size_t k) const {
    std::string_view s = tok[k];
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range)
      fail("field " + std::to_string(k) + " '" + excerpt(tok[k]) + "' is out of range");
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) {
      fail("field " + std::to_string(k) + " '" + excerpt(tok[k]) + "' is not a number");
    }
    if (!std::isfinite(v))
      fail("field " + std::to_string(k) + " is " + excerpt(tok[k]) + " (NaN/Inf not allowed)");
    return v;
  }

  VariableId id_at(std::size_t k) const {
    std::string_view s = tok[k];
    VariableId v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size()) {
      fail("field " + std::to_string(k) + " '" + excerpt(s) + "' is not an integer vertex id");
    }
    return v;
  }
};

// Reads an upper-triangular (row by row) information matrix of size d starting at field k.
Eigen::MatrixXd readInformation(const Line& line, std::size_t k, int d, const G2oReadOptions& opt,
                                G2oReadReport* report) {
  Eigen::MatrixXd m(d, d);
  for (int r = 0; r < d; ++r) {
    for (int c = r; c < d; ++c) {
      m(r, c) = m(c, r) = line.number_at(k++);
    }
  }
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  if (llt.info() == Eigen::Success) return m;
  if (opt.information_fix == G2oReadOptions::InformationFix::kReject) {
    line.fail("information matrix is not symmetric positive definite (use --fix-information clamp to project it)");
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
  Eigen::VectorXd ev = es.eigenvalues();
  const double scale = ev.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) line.fail("information matrix is zero");
  const double floor = 1e-9 * std::max(ev.maxCoeff(), scale);
  for (int i = 0; i < d; ++i) ev[i] = std::max(ev[i], floor);
  Eigen::MatrixXd fixed = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
  fixed = 0.5 * (fixed + fixed.transpose());
  if (report != nullptr) ++report->clamped_information;
  return fixed;
}

Eigen::Quaterniond readQuaternion(const Line& line, std::size_t k) {
  Eigen::Quaterniond q(line.number_at(k + 3), line.number_at(k), line.number_at(k + 1), line.number_at(k + 2));
  const double n = q.norm();
  if (!(n > 1e-12)) line.fail("quaternion has zero norm");
  q.coeffs() /= n;
  return q;
}

}  // namespace

PoseGraph readG2o(std::istream& in, const std::string& name, const G2oReadOptions& options,
                  G2oReadReport* report) {
  PoseGraph graph;
  std::vector<std::pair<std::size_t, std::string>> edges;  // (line number, text), resolved after vertices
  std::set<std::string> warned_tags;
  std::string text;
  std::size_t number = 0;
  auto split = [](const std::string& s, std::vector<std::string_view>& out) {
    out.clear();
    std::size_t i = 0;
    const std::size_t n = s.size();
    while (i < n) {
      while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\v' || s[i] == '\f')) ++i;
      if (i >= n) break;
      std::size_t j = i;
      while (j < n && !(s[j] == ' ' || s[j] == '\t' || s[j] == '\r' || s[j] == '\v' || s[j] == '\f')) ++j;
      out.emplace_back(s.data() + i, j - i);
      i = j;
    }
  };
  Line line{&name, 0, {}};
  while (std::getline(in, text)) {
    ++number;
    line.number = number;
    split(text, line.tok);
    if (line.tok.empty() || line.tok[0].front() == '#') continue;
    const std::string_view tag = line.tok[0];
    try {
      if (tag == "VERTEX_SE2") {
        line.expectFields(5);
        const VariableId id = line.id_at(1);
        if (graph.hasVariable(id)) line.fail("duplicate vertex id " + std::to_string(id));
        graph.addPose2(id, Pose2{Eigen::Vector2d(line.number_at(2), line.number_at(3)), line.number_at(4)});
      } else if (tag == "VERTEX_SE3:QUAT") {
        line.expectFields(9);
        const VariableId id = line.id_at(1);
        if (graph.hasVariable(id)) line.fail("duplicate vertex id " + std::to_string(id));
        Pose3 p;
        p.t = Eigen::Vector3d(line.number_at(2), line.number_at(3), line.number_at(4));
        p.q = readQuaternion(line, 5);
        graph.addPose3(id, p);
      } else if (tag == "VERTEX_XY") {
        line.expectFields(4);
        const VariableId id = line.id_at(1);
        if (graph.hasVariable(id)) line.fail("duplicate vertex id " + std::to_string(id));
        graph.addPoint2(id, Eigen::Vector2d(line.number_at(2), line.number_at(3)));
      } else if (tag == "EDGE_SE2" || tag == "EDGE_SE3:QUAT" || tag == "EDGE_SE2_XY" || tag == "EDGE_PRIOR_SE2" ||
                 tag == "FIX") {
        edges.emplace_back(number, text);
      } else if (options.skip_unknown_tags) {
        if (report != nullptr) {
          ++report->skipped_lines;
          if (warned_tags.insert(std::string(tag)).second) {
            report->warnings.push_back(name + ":" + std::to_string(number) + ": skipping unknown tag " +
                                       excerpt(tag));
          }
        }
      } else {
        line.fail("unknown tag '" + excerpt(tag) + "'");
      }
    } catch (const std::invalid_argument& e) {
      line.fail(e.what());
    }
  }
  if (in.bad()) throw G2oError(name, number, "read error");

  std::vector<std::size_t> factor_lines;  // file line of each factor, in graph.factors() order
  for (auto& [num, etext] : edges) {
    line.number = num;
    split(etext, line.tok);
    const std::string_view tag = line.tok[0];
    auto vertex = [&](std::size_t k) {
      const VariableId id = line.id_at(k);
      if (!graph.hasVariable(id)) line.fail("edge names missing vertex " + std::to_string(id));
      return id;
    };
    try {
      if (tag == "FIX") {
        if (line.tok.size() < 2) line.fail("FIX needs at least one vertex id");
        for (std::size_t k = 1; k < line.tok.size(); ++k) graph.setFixed(vertex(k), true);
      } else if (tag == "EDGE_SE2") {
        line.expectFields(12);
        const VariableId i = vertex(1), j = vertex(2);
        const Pose2 z{Eigen::Vector2d(line.number_at(3), line.number_at(4)), line.number_at(5)};
        const Eigen::Matrix3d info = readInformation(line, 6, 3, options, report);
        graph.addBetween2(i, j, z, info);
      } else if (tag == "EDGE_SE3:QUAT") {
        line.expectFields(31);
        const VariableId i = vertex(1), j = vertex(2);
        Pose3 z;
        z.t = Eigen::Vector3d(line.number_at(3), line.number_at(4), line.number_at(5));
        z.q = readQuaternion(line, 6);
        const Matrix6d info = readInformation(line, 10, 6, options, report);
        graph.addBetween3(i, j, z, info);
      } else if (tag == "EDGE_SE2_XY") {
        line.expectFields(8);
        const VariableId i = vertex(1), j = vertex(2);
        const Eigen::Vector2d z(line.number_at(3), line.number_at(4));
        const Eigen::Matrix2d info = readInformation(line, 5, 2, options, report);
        graph.addPose2Point2(i, j, z, info);
      } else if (tag == "EDGE_PRIOR_SE2") {
        line.expectFields(11);
        const VariableId i = vertex(1);
        const Pose2 z{Eigen::Vector2d(line.number_at(2), line.number_at(3)), line.number_at(4)};
        const Eigen::Matrix3d info = readInformation(line, 5, 3, options, report);
        graph.addPrior2(i, z, info);
      }
    } catch (const std::invalid_argument& e) {
      line.fail(e.what());  // kind mismatch, self loop, ...
    }
    factor_lines.resize(graph.factors().size(), num);
  }
  // Finite numbers can still overflow the cost (e.g. 1e300 m): the optimizer would start from an infinite
  // chi2.
  const auto& values = graph.variables();
  for (std::size_t k = 0; k < graph.factors().size(); ++k) {
    const Factor& f = graph.factors()[k];
    const int d = errorDim(f.kind);
    const Vector6d e = factorError(f, values);
    if (!std::isfinite(e.head(d).dot(f.information.topLeftCorner(d, d) * e.head(d))))
      throw G2oError(name, factor_lines[k],
                     "the edge's chi2 at the initial values is not finite (values too large)");
  }
  return graph;
}

PoseGraph readG2o(const std::string& path, const G2oReadOptions& options, G2oReadReport* report) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw G2oError(path, 0, "cannot open file: is a directory");
  std::ifstream in(path);
  if (!in) throw G2oError(path, 0, "cannot open file");
  return readG2o(in, path, options, report);
}

namespace {

struct Writer {
  std::ostream& out;
  char buf[64];
  void num(double v) {
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out << ' ';
    out.write(buf, r.ptr - buf);
  }
  void id(VariableId v) { out << ' ' << v; }
  void info(const Matrix6d& m, int d) {
    for (int r = 0; r < d; ++r) {
      for (int c = r; c < d; ++c) num(m(r, c));
    }
  }
};

}  // namespace

void writeG2o(const PoseGraph& graph, std::ostream& out) {
  Writer w{out, {}};
  const auto& vars = graph.variables();
  std::vector<VariableId> fixed;
  for (const Variable& v : vars) {
    switch (v.kind) {
      case VariableKind::kPose2:
        out << "VERTEX_SE2";
        w.id(v.id);
        w.num(v.pose2.t.x());
        w.num(v.pose2.t.y());
        w.num(v.pose2.theta);
        break;
      case VariableKind::kPose3:
        out << "VERTEX_SE3:QUAT";
        w.id(v.id);
        for (int k = 0; k < 3; ++k) w.num(v.pose3.t[k]);
        for (int k = 0; k < 4; ++k) w.num(v.pose3.q.coeffs()[k]);  // x y z w
        break;
      case VariableKind::kPoint2:
        out << "VERTEX_XY";
        w.id(v.id);
        w.num(v.point.x());
        w.num(v.point.y());
        break;
      case VariableKind::kPoint3:
        throw std::invalid_argument("writeG2o: 3D points are not supported by the g2o writer");
    }
    out << '\n';
    if (v.fixed) fixed.push_back(v.id);
  }
  for (VariableId id : fixed) out << "FIX " << id << '\n';
  for (const Factor& f : graph.factors()) {
    const VariableId a = vars[f.var[0]].id;
    const VariableId b = arity(f.kind) == 2 ? vars[f.var[1]].id : 0;
    switch (f.kind) {
      case FactorKind::kBetween2:
        out << "EDGE_SE2";
        w.id(a);
        w.id(b);
        w.num(f.z2.t.x());
        w.num(f.z2.t.y());
        w.num(f.z2.theta);
        w.info(f.information, 3);
        break;
      case FactorKind::kBetween3:
        out << "EDGE_SE3:QUAT";
        w.id(a);
        w.id(b);
        for (int k = 0; k < 3; ++k) w.num(f.z3.t[k]);
        for (int k = 0; k < 4; ++k) w.num(f.z3.q.coeffs()[k]);
        w.info(f.information, 6);
        break;
      case FactorKind::kPose2Point2:
        out << "EDGE_SE2_XY";
        w.id(a);
        w.id(b);
        w.num(f.zp.x());
        w.num(f.zp.y());
        w.info(f.information, 2);
        break;
      case FactorKind::kPrior2:
        out << "EDGE_PRIOR_SE2";
        w.id(a);
        w.num(f.z2.t.x());
        w.num(f.z2.t.y());
        w.num(f.z2.theta);
        w.info(f.information, 3);
        break;
      case FactorKind::kPrior3:
      case FactorKind::kPose3Point3:
        throw std::invalid_argument("writeG2o: SE3 priors and SE3-point factors are not supported by the g2o writer");
    }
    out << '\n';
  }
}

void writeG2o(const PoseGraph& graph, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot open " + path + " for writing");
  writeG2o(graph, out);
  out.flush();
  if (!out) throw std::runtime_error("error writing " + path);
}

}  // namespace cairn::graph_slam
