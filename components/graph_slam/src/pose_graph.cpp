#include "cairn/graph_slam/pose_graph.hpp"

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

#include "cairn/graph_slam/factors.hpp"

namespace cairn::graph_slam {
namespace {
std::atomic<std::uint64_t> g_structure_counter{0};

const char* kindName(VariableKind k) {
  switch (k) {
    case VariableKind::kPose2: return "SE2 pose";
    case VariableKind::kPose3: return "SE3 pose";
    case VariableKind::kPoint2: return "2D point";
    case VariableKind::kPoint3: return "3D point";
  }
  return "?";
}
}  // namespace

int tangentDim(VariableKind kind) {
  switch (kind) {
    case VariableKind::kPose2: return 3;
    case VariableKind::kPose3: return 6;
    case VariableKind::kPoint2: return 2;
    case VariableKind::kPoint3: return 3;
  }
  return 0;
}

int errorDim(FactorKind kind) {
  switch (kind) {
    case FactorKind::kBetween2: return 3;
    case FactorKind::kBetween3: return 6;
    case FactorKind::kPrior2: return 3;
    case FactorKind::kPrior3: return 6;
    case FactorKind::kPose2Point2: return 2;
    case FactorKind::kPose3Point3: return 3;
  }
  return 0;
}

int arity(FactorKind kind) {
  return (kind == FactorKind::kPrior2 || kind == FactorKind::kPrior3) ? 1 : 2;
}

void PoseGraph::touchStructure() { structure_version_ = ++g_structure_counter; }

std::size_t PoseGraph::addVariable(Variable v) {
  if (index_.count(v.id) != 0) {
    throw std::invalid_argument("duplicate variable id " + std::to_string(v.id));
  }
  const std::size_t idx = variables_.size();
  index_.emplace(v.id, idx);
  variables_.push_back(std::move(v));
  touchStructure();
  return idx;
}

std::size_t PoseGraph::addPose2(VariableId id, const Pose2& value) {
  Variable v;
  v.id = id;
  v.kind = VariableKind::kPose2;
  v.pose2 = value;
  v.pose2.theta = normalizeAngle(value.theta);
  v.point.setZero();
  return addVariable(std::move(v));
}

std::size_t PoseGraph::addPose3(VariableId id, const Pose3& value) {
  Variable v;
  v.id = id;
  v.kind = VariableKind::kPose3;
  v.pose3 = value;
  v.pose3.q.normalize();
  v.point.setZero();
  return addVariable(std::move(v));
}

std::size_t PoseGraph::addPoint2(VariableId id, const Eigen::Vector2d& value) {
  Variable v;
  v.id = id;
  v.kind = VariableKind::kPoint2;
  v.point = Eigen::Vector3d(value.x(), value.y(), 0.0);
  return addVariable(std::move(v));
}

std::size_t PoseGraph::addPoint3(VariableId id, const Eigen::Vector3d& value) {
  Variable v;
  v.id = id;
  v.kind = VariableKind::kPoint3;
  v.point = value;
  return addVariable(std::move(v));
}

std::size_t PoseGraph::indexOf(VariableId id) const {
  const auto it = index_.find(id);
  if (it == index_.end()) throw std::out_of_range("unknown variable id " + std::to_string(id));
  return it->second;
}

std::size_t PoseGraph::addFactor(Factor f, VariableKind k0, VariableKind k1) {
  const int n = arity(f.kind);
  const VariableKind want[2] = {k0, k1};
  for (int a = 0; a < n; ++a) {
    const VariableKind have = variables_[f.var[a]].kind;
    if (have != want[a]) {
      throw std::invalid_argument("variable " + std::to_string(variables_[f.var[a]].id) + " is a " +
                                  kindName(have) + ", the factor needs a " + kindName(want[a]));
    }
  }
  if (n == 2 && f.var[0] == f.var[1]) {
    throw std::invalid_argument("factor connects variable " + std::to_string(variables_[f.var[0]].id) +
                                " with itself");
  }
  const int d = errorDim(f.kind);
  if (!f.information.topLeftCorner(d, d).allFinite()) throw std::invalid_argument("non-finite information");
  factors_.push_back(std::move(f));
  touchStructure();
  return factors_.size() - 1;
}

namespace {
std::size_t lookup(const PoseGraph& g, VariableId id) {
  if (!g.hasVariable(id)) throw std::invalid_argument("factor names unknown variable " + std::to_string(id));
  return g.indexOf(id);
}
}  // namespace

std::size_t PoseGraph::addBetween2(VariableId i, VariableId j, const Pose2& z, const Eigen::Matrix3d& info) {
  Factor f;
  f.kind = FactorKind::kBetween2;
  f.var = {lookup(*this, i), lookup(*this, j)};
  f.z2 = z;
  f.information.topLeftCorner<3, 3>() = info;
  return addFactor(std::move(f), VariableKind::kPose2, VariableKind::kPose2);
}

std::size_t PoseGraph::addBetween3(VariableId i, VariableId j, const Pose3& z, const Matrix6d& info) {
  Factor f;
  f.kind = FactorKind::kBetween3;
  f.var = {lookup(*this, i), lookup(*this, j)};
  f.z3 = z;
  f.z3.q.normalize();
  f.information = info;
  return addFactor(std::move(f), VariableKind::kPose3, VariableKind::kPose3);
}

std::size_t PoseGraph::addPrior2(VariableId i, const Pose2& z, const Eigen::Matrix3d& info) {
  Factor f;
  f.kind = FactorKind::kPrior2;
  f.var = {lookup(*this, i), 0};
  f.z2 = z;
  f.information.topLeftCorner<3, 3>() = info;
  return addFactor(std::move(f), VariableKind::kPose2, VariableKind::kPose2);
}

std::size_t PoseGraph::addPrior3(VariableId i, const Pose3& z, const Matrix6d& info) {
  Factor f;
  f.kind = FactorKind::kPrior3;
  f.var = {lookup(*this, i), 0};
  f.z3 = z;
  f.z3.q.normalize();
  f.information = info;
  return addFactor(std::move(f), VariableKind::kPose3, VariableKind::kPose3);
}

std::size_t PoseGraph::addPose2Point2(VariableId pose, VariableId point, const Eigen::Vector2d& z,
                                      const Eigen::Matrix2d& info) {
  Factor f;
  f.kind = FactorKind::kPose2Point2;
  f.var = {lookup(*this, pose), lookup(*this, point)};
  f.zp = Eigen::Vector3d(z.x(), z.y(), 0.0);
  f.information.topLeftCorner<2, 2>() = info;
  return addFactor(std::move(f), VariableKind::kPose2, VariableKind::kPoint2);
}

std::size_t PoseGraph::addPose3Point3(VariableId pose, VariableId point, const Eigen::Vector3d& z,
                                      const Eigen::Matrix3d& info) {
  Factor f;
  f.kind = FactorKind::kPose3Point3;
  f.var = {lookup(*this, pose), lookup(*this, point)};
  f.zp = z;
  f.information.topLeftCorner<3, 3>() = info;
  return addFactor(std::move(f), VariableKind::kPose3, VariableKind::kPoint3);
}

void PoseGraph::setFixed(VariableId id, bool fixed) {
  Variable& v = variables_[indexOf(id)];
  if (v.fixed != fixed) {
    v.fixed = fixed;
    touchStructure();
  }
}

void PoseGraph::setRobustKernel(std::size_t factor, const RobustKernel& kernel) {
  factors_.at(factor).kernel = kernel;
}

void PoseGraph::setRobustKernelAll(const RobustKernel& kernel) {
  for (Factor& f : factors_) f.kernel = kernel;
}

void PoseGraph::setFactorWeight(std::size_t factor, double weight) {
  if (!(weight >= 0.0) || !std::isfinite(weight)) throw std::invalid_argument("factor weight must be >= 0");
  factors_.at(factor).weight = weight;
}

const Pose2& PoseGraph::pose2(VariableId id) const {
  const Variable& v = variable(id);
  if (v.kind != VariableKind::kPose2) throw std::invalid_argument("variable is not an SE2 pose");
  return v.pose2;
}

const Pose3& PoseGraph::pose3(VariableId id) const {
  const Variable& v = variable(id);
  if (v.kind != VariableKind::kPose3) throw std::invalid_argument("variable is not an SE3 pose");
  return v.pose3;
}

void PoseGraph::setPose2(VariableId id, const Pose2& value) {
  Variable& v = variables_[indexOf(id)];
  if (v.kind != VariableKind::kPose2) throw std::invalid_argument("variable is not an SE2 pose");
  v.pose2 = Pose2{value.t, normalizeAngle(value.theta)};
}

void PoseGraph::setPose3(VariableId id, const Pose3& value) {
  Variable& v = variables_[indexOf(id)];
  if (v.kind != VariableKind::kPose3) throw std::invalid_argument("variable is not an SE3 pose");
  v.pose3 = value;
  v.pose3.q.normalize();
}

void PoseGraph::setPoint(VariableId id, const Eigen::Vector3d& value) {
  Variable& v = variables_[indexOf(id)];
  if (v.kind != VariableKind::kPoint2 && v.kind != VariableKind::kPoint3) {
    throw std::invalid_argument("variable is not a point");
  }
  v.point = value;
  if (v.kind == VariableKind::kPoint2) v.point.z() = 0.0;
}

void PoseGraph::setValues(const std::vector<Variable>& values) {
  if (values.size() != variables_.size()) throw std::invalid_argument("setValues: size mismatch");
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (values[k].id != variables_[k].id || values[k].kind != variables_[k].kind) {
      throw std::invalid_argument("setValues: variable mismatch");
    }
    variables_[k].pose2 = values[k].pose2;
    variables_[k].pose3 = values[k].pose3;
    variables_[k].point = values[k].point;
  }
}

Vector6d factorError(const Factor& f, const std::vector<Variable>& values) {
  Vector6d e = Vector6d::Zero();
  const Variable& a = values[f.var[0]];
  switch (f.kind) {
    case FactorKind::kBetween2:
      e.head<3>() = errorBetween2(a.pose2, values[f.var[1]].pose2, f.z2, nullptr, nullptr);
      break;
    case FactorKind::kBetween3:
      e = errorBetween3(a.pose3, values[f.var[1]].pose3, f.z3, nullptr, nullptr);
      break;
    case FactorKind::kPrior2: e.head<3>() = errorPrior2(a.pose2, f.z2, nullptr); break;
    case FactorKind::kPrior3: e = errorPrior3(a.pose3, f.z3, nullptr); break;
    case FactorKind::kPose2Point2:
      e.head<2>() = errorPose2Point2(a.pose2, values[f.var[1]].point.head<2>(), f.zp.head<2>(), nullptr, nullptr);
      break;
    case FactorKind::kPose3Point3:
      e.head<3>() = errorPose3Point3(a.pose3, values[f.var[1]].point, f.zp, nullptr, nullptr);
      break;
  }
  return e;
}

double PoseGraph::chi2() const {
  double sum = 0.0;
  for (const Factor& f : factors_) {
    const int d = errorDim(f.kind);
    const Vector6d e = factorError(f, variables_);
    sum += e.head(d).dot(f.information.topLeftCorner(d, d) * e.head(d));
  }
  return sum;
}

double PoseGraph::robustCost() const {
  double sum = 0.0;
  for (const Factor& f : factors_) {
    const int d = errorDim(f.kind);
    const Vector6d e = factorError(f, variables_);
    const double s = f.weight * e.head(d).dot(f.information.topLeftCorner(d, d) * e.head(d));
    double rho = 0.0, drho = 0.0;
    f.kernel.evaluate(s, rho, drho);
    sum += rho;
  }
  return sum;
}

}  // namespace cairn::graph_slam
