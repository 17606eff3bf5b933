// The factor graph: SE2/SE3 poses and 2D/3D points (variables), relative-pose, prior and pose-point factors
// with full information matrices (Stüde §3.1.1, eqs. 3.3-3.5).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/robust_kernel.hpp"

namespace cairn::graph_slam {

using VariableId = std::int64_t;

enum class VariableKind : std::uint8_t { kPose2, kPose3, kPoint2, kPoint3 };
enum class FactorKind : std::uint8_t { kBetween2, kBetween3, kPrior2, kPrior3, kPose2Point2, kPose3Point3 };

/// Dimension of a variable's tangent space (3, 6, 2, 3).
int tangentDim(VariableKind kind);
/// Dimension of a factor's error vector (3, 6, 3, 6, 2, 3).
int errorDim(FactorKind kind);
/// Number of variables a factor connects (1 for priors, else 2).
int arity(FactorKind kind);

struct Variable {
  VariableId id = 0;
  VariableKind kind = VariableKind::kPose2;
  bool fixed = false;
  Pose2 pose2;            ///< kPose2
  Pose3 pose3;            ///< kPose3
  Eigen::Vector3d point;  ///< kPoint2 (x, y, 0) and kPoint3
};

struct Factor {
  FactorKind kind = FactorKind::kBetween2;
  std::array<std::size_t, 2> var{0, 0};  ///< indices into PoseGraph::variables() (var[1] unused by priors)
  Pose2 z2;                              ///< measurement of kBetween2 / kPrior2
  Pose3 z3;                              ///< measurement of kBetween3 / kPrior3
  Eigen::Vector3d zp = Eigen::Vector3d::Zero();  ///< measurement of pose-point factors
  Matrix6d information = Matrix6d::Zero();       ///< top-left errorDim x errorDim block is used
  RobustKernel kernel;
  /// Extra scale of the information (used by GNC); 1 for ordinary factors.
  double weight = 1.0;
};

class PoseGraph {
 public:
  PoseGraph() = default;

  // Variables. Ids are unique across all kinds; adding an existing id throws std::invalid_argument.
  std::size_t addPose2(VariableId id, const Pose2& value);
  std::size_t addPose3(VariableId id, const Pose3& value);
  std::size_t addPoint2(VariableId id, const Eigen::Vector2d& value);
  std::size_t addPoint3(VariableId id, const Eigen::Vector3d& value);

  // Factors; unknown ids, kind mismatches or information matrices of the wrong size throw
  // std::invalid_argument. Returns the factor index.
  std::size_t addBetween2(VariableId i, VariableId j, const Pose2& z, const Eigen::Matrix3d& information);
  std::size_t addBetween3(VariableId i, VariableId j, const Pose3& z, const Matrix6d& information);
  std::size_t addPrior2(VariableId i, const Pose2& z, const Eigen::Matrix3d& information);
  std::size_t addPrior3(VariableId i, const Pose3& z, const Matrix6d& information);
  std::size_t addPose2Point2(VariableId pose, VariableId point, const Eigen::Vector2d& z,
                             const Eigen::Matrix2d& information);
  std::size_t addPose3Point3(VariableId pose, VariableId point, const Eigen::Vector3d& z,
                             const Eigen::Matrix3d& information);

  void setFixed(VariableId id, bool fixed = true);
  void setRobustKernel(std::size_t factor, const RobustKernel& kernel);
  /// Sets the kernel of every factor (priors included).
  void setRobustKernelAll(const RobustKernel& kernel);
  void setFactorWeight(std::size_t factor, double weight);

  bool hasVariable(VariableId id) const { return index_.count(id) != 0; }
  std::size_t indexOf(VariableId id) const;  ///< throws std::out_of_range
  const std::vector<Variable>& variables() const { return variables_; }
  const std::vector<Factor>& factors() const { return factors_; }
  const Variable& variable(VariableId id) const { return variables_[indexOf(id)]; }

  const Pose2& pose2(VariableId id) const;
  const Pose3& pose3(VariableId id) const;
  void setPose2(VariableId id, const Pose2& value);
  void setPose3(VariableId id, const Pose3& value);
  void setPoint(VariableId id, const Eigen::Vector3d& value);

  /// Replaces all values at once (same size and kinds as variables()); does not change the structure.
  void setValues(const std::vector<Variable>& values);

  /// Changes whenever variables, factors or the fixed set change (not when values, kernels or weights do).
  /// Unique across all graphs of the process, so an optimizer can cache its symbolic analysis by it.
  std::uint64_t structureVersion() const { return structure_version_; }

  /// sum e^T Omega e over all factors (Stüde eq. 3.4), without robust kernels and weights.
  double chi2() const;
  /// sum weight * rho(e^T Omega e), the objective the optimizer minimizes.
  double robustCost() const;

 private:
  std::size_t addVariable(Variable v);
  std::size_t addFactor(Factor f, VariableKind k0, VariableKind k1);
  void touchStructure();

  std::vector<Variable> variables_;
  std::vector<Factor> factors_;
  std::unordered_map<VariableId, std::size_t> index_;
  std::uint64_t structure_version_ = 0;
};

/// Error vector of one factor at the given variable values (errorDim(kind) entries used).
Vector6d factorError(const Factor& f, const std::vector<Variable>& values);

}  // namespace cairn::graph_slam
