#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tangent::contact {

/// Body coordinates q_B = [p_WB (3), Q_WB (4)], quaternion ordered (w, x, y, z) (design.md §3).
using Vector7d = Eigen::Matrix<double, 7, 1>;
using Matrix34d = Eigen::Matrix<double, 3, 4>;
using Matrix37d = Eigen::Matrix<double, 3, 7>;

inline Eigen::Vector3d Position(const Vector7d& q) { return q.head<3>(); }
inline Eigen::Vector4d Quaternion(const Vector7d& q) { return q.tail<4>(); }

/// R_WB of the *normalized* quaternion Q/|Q|. Bodies are placed with the normalized rotation,
/// so a coordinate vector whose Q drifted off the unit sphere still describes a rigid pose, and
/// every derivative with respect to Q is orthogonal to Q (moving along Q moves nothing).
/// @pre |Q| > 0.
Eigen::Matrix3d RotationMatrix(const Eigen::Vector4d& Q);

/// ∂(Q v Q*)/∂Q for the unnormalized product Q v Q* = (w² − r·r) v + 2w r×v + 2 r (r·v),
/// Q = (w, r) (seed 001 Appendix B, Eq. 25, rederived: the OCR of Eq. 25 lost the factor 2 and
/// scrambled entries):
///   ∂/∂w = 2 (w v + r × v),   ∂/∂r = 2 ((r·v) I + r vᵀ − v rᵀ − w [v]×).
/// (3 x 4, columns w, x, y, z.)
Matrix34d RotateDerivativeUnnormalized(const Eigen::Vector4d& Q, const Eigen::Vector3d& v);

/// ∂(R(Q/|Q|) v)/∂Q = ∂(Q̂vQ̂*)/∂Q̂ · (I − Q̂Q̂ᵀ)/|Q|, Q̂ = Q/|Q|: the derivative of a body-fixed
/// vector v (body frame) expressed in the world, used for every placed point and partial.
/// At unit Q it equals −[R v]× · R · G(Q) (rigid rotation, checked in tests).
Matrix34d RotateDerivative(const Eigen::Vector4d& Q, const Eigen::Vector3d& v);

/// The rate operator of seed 001 Eq. 17, G(Q) = 2 [−x w z −y; −y −z w x; −z y −x w], which maps
/// Q̇ to the angular velocity **in the body frame**: w_B = G(Q) Q̇ for unit Q. G(Q) Q = 0.
/// The torque equivalent of a generalized force W_c on the quaternion coordinates is
/// τ_B = ¼ G(Q) W_c (seed 001 Eq. 5), also in the body frame.
Matrix34d GBody(const Eigen::Vector4d& Q);
/// R(Q) G(Q): maps Q̇ to the angular velocity in the world frame, w_W = GWorld(Q) Q̇.
Matrix34d GWorld(const Eigen::Vector4d& Q);

/// τ_B = ¼ G(Q) W_c: the body-frame torque that does the same work as the generalized force W_c
/// on Q under any unit-norm-preserving motion. @pre |Q| = 1.
inline Eigen::Vector3d TorqueFromQuaternionForce(const Eigen::Vector4d& Q,
                                                 const Eigen::Vector4d& W_c) {
  return 0.25 * GBody(Q) * W_c;
}

/// ∇²_Q [yᵀ R(Q/|Q|) v] (4 x 4): the second derivative of one world component combination of a
/// body-fixed vector under the normalized map. With Q v Q* = φ-form Qᵀ A Q, where
///   A = [y·v, (v×y)ᵀ; v×y, −(y·v)I + y vᵀ + v yᵀ],
/// f(Q) = QᵀAQ / QᵀQ and ∇²f = 2A/s − 4(AQQᵀ + QQᵀA)/s² − 2φ I/s² + 8φ QQᵀ/s³, s = QᵀQ, φ = QᵀAQ.
Eigen::Matrix4d RotateHessian(const Eigen::Vector4d& Q, const Eigen::Vector3d& v,
                              const Eigen::Vector3d& y);
/// Σ_k ∇²_Q [y_kᵀ R(Q/|Q|) v_k] for the weight W = Σ_k y_k v_kᵀ (3 x 3): the Hessian is linear
/// in y vᵀ (A above is), so every curvature a body's rotation contributes to a Newton matrix is
/// accumulated into one W and folded once per body.
Eigen::Matrix4d RotateHessianWeighted(const Eigen::Vector4d& Q, const Eigen::Matrix3d& W);

/// [a]×, the cross-product matrix: [a]× b = a × b.
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

}  // namespace tangent::contact
