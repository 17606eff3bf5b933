#include "cairn/graph_slam/factors.hpp"

#include <cmath>

namespace cairn::graph_slam {

Eigen::Vector3d errorBetween2(const Pose2& xi, const Pose2& xj, const Pose2& z, Eigen::Matrix3d* jac_i,
                              Eigen::Matrix3d* jac_j) {
  return errorBetween2(xi, xj, z, std::cos(xi.theta), std::sin(xi.theta), std::cos(z.theta), std::sin(z.theta), jac_i,
                       jac_j);
}

Eigen::Vector3d errorBetween2(const Pose2& xi, const Pose2& xj, const Pose2& z, double ci, double si, double cz,
                              double sz, Eigen::Matrix3d* jac_i, Eigen::Matrix3d* jac_j) {
  // Stüde eq. 3.3 in SE(2): relative pose Xi^-1 Xj, then the measurement removed: Z^-1 (Xi^-1 Xj).
  const Eigen::Vector2d d = xj.t - xi.t;
  const Eigen::Vector2d t_ij(ci * d.x() + si * d.y(), -si * d.x() + ci * d.y());  // Ri^T d
  const Eigen::Vector2d u = t_ij - z.t;
  Eigen::Vector3d e;
  e.x() = cz * u.x() + sz * u.y();  // Rz^T u
  e.y() = -sz * u.x() + cz * u.y();
  e.z() = normalizeAngle(xj.theta - xi.theta - z.theta);
  if (jac_i != nullptr || jac_j != nullptr) {
    Eigen::Matrix2d rzt;
    rzt << cz, sz, -sz, cz;
    Eigen::Matrix2d rit;
    rit << ci, si, -si, ci;
    const Eigen::Matrix2d a = rzt * rit;                          // d e_t / d t_j
    const Eigen::Vector2d dri(-si * d.x() + ci * d.y(), -ci * d.x() - si * d.y());  // dRi^T/dtheta d
    if (jac_i != nullptr) {
      jac_i->setZero();
      jac_i->topLeftCorner<2, 2>() = -a;
      jac_i->block<2, 1>(0, 2) = rzt * dri;
      (*jac_i)(2, 2) = -1.0;
    }
    if (jac_j != nullptr) {
      jac_j->setZero();
      jac_j->topLeftCorner<2, 2>() = a;
      (*jac_j)(2, 2) = 1.0;
    }
  }
  return e;
}

Vector6d errorBetween3(const Pose3& xi, const Pose3& xj, const Pose3& z, Matrix6d* jac_i, Matrix6d* jac_j) {
  // Stüde eq. 3.3 in SE(3) with g2o's pi(): translation and quaternion vector part (w >= 0).
  const Eigen::Matrix3d ri = xi.q.toRotationMatrix();
  const Eigen::Matrix3d rzt = z.q.toRotationMatrix().transpose();
  const Eigen::Vector3d t_ij = ri.transpose() * (xj.t - xi.t);
  Eigen::Quaterniond qe = z.q.conjugate() * (xi.q.conjugate() * xj.q);
  qe.normalize();
  if (qe.w() < 0.0) qe.coeffs() = -qe.coeffs();
  Vector6d e;
  e.head<3>() = rzt * (t_ij - z.t);
  e.tail<3>() = qe.vec();
  if (jac_i != nullptr || jac_j != nullptr) {
    const double w = qe.w();
    const Eigen::Matrix3d sv = skew(qe.vec());
    if (jac_i != nullptr) {
      // Xi <- Xi * Exp(d): t_ij <- t_ij - dt + [t_ij]x dw; Re <- Exp(-Rz^T dw) Re.
      jac_i->setZero();
      jac_i->topLeftCorner<3, 3>() = -rzt;
      jac_i->topRightCorner<3, 3>() = rzt * skew(t_ij);
      jac_i->bottomRightCorner<3, 3>() = -0.5 * (w * Eigen::Matrix3d::Identity() - sv) * rzt;
    }
    if (jac_j != nullptr) {
      // Xj <- Xj * Exp(d): t_ij <- t_ij + Ri^T Rj dt; Re <- Re Exp(dw).
      jac_j->setZero();
      jac_j->topLeftCorner<3, 3>() = rzt * ri.transpose() * xj.q.toRotationMatrix();
      jac_j->bottomRightCorner<3, 3>() = 0.5 * (w * Eigen::Matrix3d::Identity() + sv);
    }
  }
  return e;
}

Eigen::Vector3d errorPrior2(const Pose2& x, const Pose2& z, Eigen::Matrix3d* jac) {
  return errorBetween2(Pose2{}, x, z, nullptr, jac);
}

Vector6d errorPrior3(const Pose3& x, const Pose3& z, Matrix6d* jac) {
  return errorBetween3(Pose3{}, x, z, nullptr, jac);
}

Eigen::Vector2d errorPose2Point2(const Pose2& x, const Eigen::Vector2d& p, const Eigen::Vector2d& z,
                                 Eigen::Matrix<double, 2, 3>* jac_x, Eigen::Matrix2d* jac_p) {
  const double c = std::cos(x.theta), s = std::sin(x.theta);
  const Eigen::Vector2d d = p - x.t;
  Eigen::Matrix2d rt;
  rt << c, s, -s, c;
  if (jac_x != nullptr) {
    jac_x->leftCols<2>() = -rt;
    jac_x->col(2) = Eigen::Vector2d(-s * d.x() + c * d.y(), -c * d.x() - s * d.y());
  }
  if (jac_p != nullptr) *jac_p = rt;
  return rt * d - z;
}

Eigen::Vector3d errorPose3Point3(const Pose3& x, const Eigen::Vector3d& p, const Eigen::Vector3d& z,
                                 Eigen::Matrix<double, 3, 6>* jac_x, Eigen::Matrix3d* jac_p) {
  const Eigen::Matrix3d rt = x.q.toRotationMatrix().transpose();
  const Eigen::Vector3d l = rt * (p - x.t);
  if (jac_x != nullptr) {
    jac_x->leftCols<3>() = -Eigen::Matrix3d::Identity();
    jac_x->rightCols<3>() = skew(l);
  }
  if (jac_p != nullptr) *jac_p = rt;
  return l - z;
}

}  // namespace cairn::graph_slam
