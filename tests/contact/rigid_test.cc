// Quaternion derivatives (seed 001 Eq. 25, rederived) and the rate operator G (Eq. 17) against
// central finite differences. h = 1e-6 on O(1) quantities: truncation ~h² = 1e-12, rounding
// ~eps/h = 2e-10, so 1e-8 absolute is a safe bar with two digits of margin.

#include "contact/rigid.h"

#include <gtest/gtest.h>

#include <random>

namespace tangent::contact {
namespace {

constexpr double kH = 1e-6;
constexpr double kTol = 1e-8;

Eigen::Vector4d RandomUnitQuaternion(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized();
}

Eigen::Vector3d QvQstar(const Eigen::Vector4d& Q, const Eigen::Vector3d& v) {
  const double w = Q[0];
  const Eigen::Vector3d r = Q.tail<3>();
  return (w * w - r.dot(r)) * v + 2 * w * r.cross(v) + 2 * r * r.dot(v);
}

TEST(RigidTest, UnnormalizedRotateDerivativeMatchesFiniteDifferences) {
  std::mt19937_64 rng(1);
  for (int k = 0; k < 20; ++k) {
    // Deliberately non-unit Q: the formula is for the plain product Q v Q*.
    const Eigen::Vector4d Q = 1.3 * RandomUnitQuaternion(rng);
    const Eigen::Vector3d v = Eigen::Vector3d::Random();
    const Matrix34d d = RotateDerivativeUnnormalized(Q, v);
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector4d e = Eigen::Vector4d::Unit(i) * kH;
      const Eigen::Vector3d fd = (QvQstar(Q + e, v) - QvQstar(Q - e, v)) / (2 * kH);
      EXPECT_LT((d.col(i) - fd).norm(), kTol) << "column " << i;
    }
  }
}

TEST(RigidTest, NormalizedRotateDerivativeMatchesFiniteDifferencesAndRigidForm) {
  std::mt19937_64 rng(2);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector4d Q = RandomUnitQuaternion(rng);
    const Eigen::Vector3d v = Eigen::Vector3d::Random();
    const Matrix34d d = RotateDerivative(Q, v);
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector4d e = Eigen::Vector4d::Unit(i) * kH;
      const Eigen::Vector3d fd = (RotationMatrix(Q + e) * v - RotationMatrix(Q - e) * v) / (2 * kH);
      EXPECT_LT((d.col(i) - fd).norm(), kTol);
    }
    // At unit Q: ∂(R v)/∂Q = −[R v]× R G(Q), i.e. the velocity w × (R v) of a rigid rotation.
    const Eigen::Matrix3d R = RotationMatrix(Q);
    EXPECT_LT((d - (-Skew(R * v) * R * GBody(Q))).norm(), 1e-14);
    EXPECT_LT((d * Q).norm(), 1e-14);  // Moving along Q moves nothing.
  }
}

TEST(RigidTest, RotateHessianMatchesFiniteDifferences) {
  std::mt19937_64 rng(4);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector4d Q = 0.8 * RandomUnitQuaternion(rng);  // Off the unit sphere too.
    const Eigen::Vector3d v = Eigen::Vector3d::Random(), y = Eigen::Vector3d::Random();
    const Eigen::Matrix4d H = RotateHessian(Q, v, y);
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector4d e = Eigen::Vector4d::Unit(i) * kH;
      const Eigen::Vector4d fd =
          (y.transpose() * RotateDerivative(Q + e, v) - y.transpose() * RotateDerivative(Q - e, v))
              .transpose() /
          (2 * kH);
      EXPECT_LT((H.col(i) - fd).norm(), kTol);
    }
  }
}

TEST(RigidTest, WeightedRotateHessianIsTheSumOfItsOuterProducts) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector4d Q = 1.3 * RandomUnitQuaternion(rng);
    Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
    Eigen::Matrix4d sum = Eigen::Matrix4d::Zero();
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d v = Eigen::Vector3d::Random(), y = Eigen::Vector3d::Random();
      W += y * v.transpose();
      sum += RotateHessian(Q, v, y);
    }
    EXPECT_LT((RotateHessianWeighted(Q, W) - sum).norm(), 1e-13);
  }
}

TEST(RigidTest, GBodyGivesBodyAngularVelocityAndTorqueMapConservesPower) {
  std::mt19937_64 rng(3);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector4d Q = RandomUnitQuaternion(rng);
    Eigen::Vector4d Qdot = Eigen::Vector4d::Random();
    Qdot -= Q * Q.dot(Qdot);  // Unit-norm-preserving motion.
    // R(t) = R(Q + t Q̇): Rᵀ Ṙ = [w_B]×, Ṙ Rᵀ = [w_W]×.
    const Eigen::Matrix3d R = RotationMatrix(Q);
    const Eigen::Matrix3d Rdot =
        (RotationMatrix(Q + kH * Qdot) - RotationMatrix(Q - kH * Qdot)) / (2 * kH);
    const Eigen::Matrix3d wB = R.transpose() * Rdot, wW = Rdot * R.transpose();
    const Eigen::Vector3d omega_B(wB(2, 1), wB(0, 2), wB(1, 0));
    const Eigen::Vector3d omega_W(wW(2, 1), wW(0, 2), wW(1, 0));
    EXPECT_LT((GBody(Q) * Qdot - omega_B).norm(), kTol);
    EXPECT_LT((GWorld(Q) * Qdot - omega_W).norm(), kTol);
    EXPECT_LT((GBody(Q) * Q).norm(), 1e-15);
    // τ = ¼ G W_c does the work of W_c: W_cᵀ Q̇ = τᵀ w_B for any tangent Q̇.
    const Eigen::Vector4d Wc = Eigen::Vector4d::Random();
    Eigen::Vector4d Wt = Wc - Q * Q.dot(Wc);  // The force's tangent part does the work.
    EXPECT_NEAR(Wt.dot(Qdot), TorqueFromQuaternionForce(Q, Wc).dot(GBody(Q) * Qdot), 1e-13);
  }
}

}  // namespace
}  // namespace tangent::contact
