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
  return RotateHessianWeighted(Q, y * v.transpose());
}

Eigen::Matrix4d RotateHessianWeighted(const Eigen::Vector4d& Q, const Eigen::Matrix3d& W) {
  // A(y vᵀ) with y·v = tr W and (v × y)_i = ε_ijk W_kj.
  Eigen::Matrix4d A;
  const double yv = W.trace();
  const Eigen::Vector3d vy(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
  A(0, 0) = yv;
  A.block<1, 3>(0, 1) = vy.transpose();
  A.block<3, 1>(1, 0) = vy;
  A.block<3, 3>(1, 1) = W + W.transpose();
  A.block<3, 3>(1, 1).diagonal().array() -= yv;
  const double inv_s = 1.0 / Q.squaredNorm();
  const Eigen::Vector4d AQ = A * Q;
  const double phi = Q.dot(AQ);
  const Eigen::Vector4d Qs = Q * inv_s;
  // 2A/s − 4(AQ Qᵀ + Q AQᵀ)/s² − 2φ I/s² + 8φ Q Qᵀ/s³.
  Eigen::Matrix4d H = (2.0 * inv_s) * A;
  H.noalias() -= (4.0 * inv_s) * (AQ * Qs.transpose() + Qs * AQ.transpose());
  H.diagonal().array() -= 2.0 * phi * inv_s * inv_s;
  H.noalias() += (8.0 * phi * inv_s) * (Qs * Qs.transpose());
  return H;
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
