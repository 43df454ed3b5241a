#include "contact/rigid.h"

namespace tangent::contact {

Eigen::Matrix3d RotationMatrix(const Eigen::Vector4d& Q) {
  return Eigen::Quaterniond(Q[0], Q[1], Q[2], Q[3]).normalized().toRotationMatrix();
}

Matrix34d RotateDerivativeUnnormalized(const Eigen::Vector4d& Q, const Eigen::Vector3d& v) {
  const double w = Q[0];
  const Eigen::Vector3d r = Q.tail<3>();
  Matrix34d d;
  d.col(0) = 2.0 * (w * v + r.cross(v));
  d.rightCols<3>() = 2.0 * (r.dot(v) * Eigen::Matrix3d::Identity() + r * v.transpose() -
                            v * r.transpose() - w * Skew(v));
  return d;
}

Matrix34d RotateDerivative(const Eigen::Vector4d& Q, const Eigen::Vector3d& v) {
  const double norm = Q.norm();
  const Eigen::Vector4d q_hat = Q / norm;
  const Eigen::Matrix4d projector = Eigen::Matrix4d::Identity() - q_hat * q_hat.transpose();
  return RotateDerivativeUnnormalized(q_hat, v) * projector / norm;
}

Matrix34d GBody(const Eigen::Vector4d& Q) {
  const double w = Q[0], x = Q[1], y = Q[2], z = Q[3];
  Matrix34d g;
  g << -x, w, z, -y,  //
      -y, -z, w, x,   //
      -z, y, -x, w;
  return 2.0 * g;
}

Matrix34d GWorld(const Eigen::Vector4d& Q) { return RotationMatrix(Q) * GBody(Q); }

}  // namespace tangent::contact
