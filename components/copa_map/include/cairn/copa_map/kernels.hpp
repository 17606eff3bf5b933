// Covariance functions of CoPA-Map (Stüde 2024, §4.2.3). Inputs are rows (x1, x2, t).
// Parameters are handled in an unconstrained space (log of every positive quantity) for Adam; analytic
// gradients are given as Σ_ij G_ij ∂K_ij/∂θ so that the SVGP can chain them without forming ∂K/∂θ.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

namespace cairn::copa_map {

class Kernel {
 public:
  virtual ~Kernel() = default;
  virtual std::string type() const = 0;
  virtual int numParams() const = 0;
  virtual Eigen::VectorXd params() const = 0;  // unconstrained (log) parameters
  virtual void setParams(const Eigen::VectorXd& p) = 0;
  virtual std::vector<std::string> paramNames() const = 0;
  // Box constraints in the unconstrained space (applied after every Adam step).
  virtual Eigen::VectorXd lowerBounds() const = 0;
  virtual Eigen::VectorXd upperBounds() const = 0;

  virtual Eigen::MatrixXd K(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) const = 0;
  virtual Eigen::VectorXd Kdiag(const Eigen::MatrixXd& X) const = 0;
  // Σ_ij G_ij ∂K(X1,X2)_ij / ∂θ_p for every unconstrained parameter θ_p.
  virtual Eigen::VectorXd gradK(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                                const Eigen::MatrixXd& G) const = 0;
  // Σ_i g_i ∂k(x_i, x_i) / ∂θ_p.
  virtual Eigen::VectorXd gradKdiag(const Eigen::MatrixXd& X, const Eigen::VectorXd& g) const = 0;
  // Input gradients of Σ_ij G_ij k(X1_i, X2_j): d1 (n1 x 3) w.r.t. the rows of X1 and d2 (n2 x 3) w.r.t. the rows
  // of X2 (either may be nullptr). Used to train the inducing inputs Z.
  virtual void gradInputs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2, const Eigen::MatrixXd& G,
                          Eigen::MatrixXd* d1, Eigen::MatrixXd* d2) const = 0;
  virtual std::unique_ptr<Kernel> clone() const = 0;
};

// One periodic component of k_t (eq. 4.10), with period p (the thesis' γ_i: sin²(π|Δt|/p)), variance σ²_t,i and
// length scale l_t,i: σ² exp(-½ sin²(π|Δt|/p) / l²).
struct PeriodicComponent {
  double variance = 0.5;
  double period = 12.0;
  double lengthscale = 1.0;
};

// k_f = k_s(x1) k_s(x2) k_t(t) (eq. 4.8) with 1D Matérn-5/2 k_s (eq. 4.9, separate length scales for x1 and x2,
// i.e. ARD) and k_t a sum of periodic components (eq. 4.10). The spatial variance σ_s² is fixed at 1: in the
// product it is not identifiable from the σ²_t,i.
// Unconstrained parameters: [log l_s1, log l_s2, (log σ²_t,i, log p_i, log l_t,i) for i = 1..ψ].
class SpatioTemporalKernel final : public Kernel {
 public:
  SpatioTemporalKernel(double ls1, double ls2, std::vector<PeriodicComponent> comps);
  std::string type() const override { return "matern52x2_periodic_sum"; }
  int numParams() const override { return 2 + 3 * static_cast<int>(comps_.size()); }
  Eigen::VectorXd params() const override;
  void setParams(const Eigen::VectorXd& p) override;
  std::vector<std::string> paramNames() const override;
  Eigen::VectorXd lowerBounds() const override;
  Eigen::VectorXd upperBounds() const override;
  Eigen::MatrixXd K(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) const override;
  Eigen::VectorXd Kdiag(const Eigen::MatrixXd& X) const override;
  Eigen::VectorXd gradK(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                        const Eigen::MatrixXd& G) const override;
  Eigen::VectorXd gradKdiag(const Eigen::MatrixXd& X, const Eigen::VectorXd& g) const override;
  void gradInputs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2, const Eigen::MatrixXd& G,
                  Eigen::MatrixXd* d1, Eigen::MatrixXd* d2) const override;
  std::unique_ptr<Kernel> clone() const override { return std::make_unique<SpatioTemporalKernel>(*this); }

  double lengthscale1() const { return ls1_; }
  double lengthscale2() const { return ls2_; }
  const std::vector<PeriodicComponent>& components() const { return comps_; }
  // Bounds (positive-space) applied to the parameters.
  double min_lengthscale = 0.05, max_lengthscale = 50.0;
  double min_period = 1.0, max_period = 1e4;
  // K and gradK evaluate the per-axis factors (Matérn in x1, x2; the periodic sum in t) once per distinct pair of
  // coordinate values and look them up per entry when that is much cheaper than evaluating every entry
  // (gridded inputs: valueTablesApply). K is bit-identical to the direct evaluation, gradK equal up to rounding.
  // false: always the direct per-entry evaluation (tests compare both).
  bool use_value_tables = true;
  // Whether K(X1, X2) / gradK would take the table path (the tables hold ≤ ¼ of n1·n2 entries).
  static bool valueTablesApply(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2);

 private:
  double ls1_, ls2_;
  std::vector<PeriodicComponent> comps_;
};

// k_g (eq. 4.11): σ_g² exp(-½ Σ_d (Δx_d / l_d)²) over (x1, x2, t) with one length scale per input dimension.
// Unconstrained parameters: [log σ_g², log l_1, log l_2, log l_t].
class RbfKernel final : public Kernel {
 public:
  RbfKernel(double variance, Eigen::Vector3d lengthscales);
  std::string type() const override { return "rbf_ard3"; }
  int numParams() const override { return 4; }
  Eigen::VectorXd params() const override;
  void setParams(const Eigen::VectorXd& p) override;
  std::vector<std::string> paramNames() const override;
  Eigen::VectorXd lowerBounds() const override;
  Eigen::VectorXd upperBounds() const override;
  Eigen::MatrixXd K(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2) const override;
  Eigen::VectorXd Kdiag(const Eigen::MatrixXd& X) const override;
  Eigen::VectorXd gradK(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2,
                        const Eigen::MatrixXd& G) const override;
  Eigen::VectorXd gradKdiag(const Eigen::MatrixXd& X, const Eigen::VectorXd& g) const override;
  void gradInputs(const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X2, const Eigen::MatrixXd& G,
                  Eigen::MatrixXd* d1, Eigen::MatrixXd* d2) const override;
  std::unique_ptr<Kernel> clone() const override { return std::make_unique<RbfKernel>(*this); }
  double variance() const { return var_; }
  const Eigen::Vector3d& lengthscales() const { return ls_; }

 private:
  double var_;
  Eigen::Vector3d ls_;
};

// Builds a kernel from its type name and unconstrained parameter vector (model files).
std::unique_ptr<Kernel> makeKernel(const std::string& type, const Eigen::VectorXd& params);

}  // namespace cairn::copa_map
