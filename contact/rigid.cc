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
  // D(Q̂, v)(I − Q̂Q̂ᵀ)/|Q| = (D − 2 (R v) Q̂ᵀ)/|Q|, because D(Q̂, v) Q̂ = 2 Q̂vQ̂* = 2 R v
  // (the product is homogeneous of degree 2): no 4 x 4 projector product.
  const double inv = 1.0 / Q.norm();
  const Eigen::Vector4d q_hat = Q * inv;
  const Matrix34d d = RotateDerivativeUnnormalized(q_hat, v);
  const Eigen::Vector3d rv = 0.5 * (d * q_hat);
  return (d - 2.0 * rv * q_hat.transpose()) * inv;
}

Eigen::Matrix4d RotateHessian(const Eigen::Vector4d& Q, const Eigen::Vector3d& v,
                              const Eigen::Vector3d& y) {
  Eigen::Matrix4d A;
  const double yv = y.dot(v);
  const Eigen::Vector3d vy = v.cross(y);
  A(0, 0) = yv;
  A.block<1, 3>(0, 1) = vy.transpose();
  A.block<3, 1>(1, 0) = vy;
  A.block<3, 3>(1, 1) = -yv * Eigen::Matrix3d::Identity() + y * v.transpose() + v * y.transpose();
  const double s = Q.squaredNorm();
  const double phi = Q.dot(A * Q);
  const Eigen::Vector4d AQ = A * Q;
  return 2.0 * A / s - 4.0 * (AQ * Q.transpose() + Q * AQ.transpose()) / (s * s) -
         2.0 * phi * Eigen::Matrix4d::Identity() / (s * s) +
         8.0 * phi * Q * Q.transpose() / (s * s * s);
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
