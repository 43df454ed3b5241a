#pragma once

#include <Eigen/Core>

#include "contact/extremal.h"

namespace tangent::contact {

/// Coordinates of a body pair, q = [q_F (7), q_G (7)].
using Matrix4x14 = Eigen::Matrix<double, 4, 14>;
using Matrix3x14 = Eigen::Matrix<double, 3, 14>;
using Row14 = Eigen::Matrix<double, 1, 14>;

/// u_q = −(∂F/∂u)⁻¹ ∂F/∂q for the pair's contact equations F (see SurfacePairEval), at an
/// extremum. The reference form. @return false when ∂F/∂u is singular (then u_q is left zero).
bool ContactJacobianImplicit(const SurfacePairEval& e, const BodyPose& pose_f,
                             const BodyPose& pose_g, Matrix4x14* u_q);

/// The closed form of seed 001 Appendix A in our notation (derivation: docs/contact.md):
///   M u̇ = [v_xy + β ω_(y,−x); σ ω_(y,−x)],   M = [R_θ E_f   −(E_g + β F_g);  R_θ F_f   −σ F_g],
/// with E = [x y]ᵀ[S_u S_v] and F = [x y]ᵀ[n_u n_v] in each surface's own contact frame, R_θ the
/// tangent-plane map from f's frame to g's, σ = n_f·n_g = ±1, and (v, ω) the velocity of G
/// relative to F at the point g, in g's frame, so that u_q = A·B with A the 4 x 4 above solved
/// by two 2 x 2 inverses (E_f, then the Schur complement H = −σF_g − R_θF_f (R_θE_f)⁻¹ M12)
/// and B the 4 x 14 map from q̇ to (v_x, v_y, ω_x, ω_y). @return false when singular.
bool ContactJacobianClosedForm(const SurfacePairEval& e, const BodyPose& pose_f,
                               const BodyPose& pose_g, Matrix4x14* u_q);

/// The B of the closed form: rows v_x, v_y, ω_x, ω_y of the relative motion of G w.r.t. F at the
/// world point p_g, in the frame (x, y, z) whose columns are given (world).
Matrix4x14 RelativeVelocityMap(const BodyPose& pose_f, const BodyPose& pose_g,
                               const Eigen::Vector3d& p_g, const Eigen::Matrix3d& frame);

/// The orthogonal-parameterization formula quoted at the start of seed 001 Appendix A (Montana;
/// Anitescu et al. for the separated case), written with II = F E⁻¹ and ĨI_f = R_θ II_f R_θ:
///   u̇_f = E_f⁻¹ R_θ (II_g + ĨI_f + β II_g ĨI_f)⁻¹ ([−ω_y; ω_x] + II_g [v_x; v_y]),
///   u̇_g = E_g⁻¹ (II_g + ĨI_f + β ĨI_f II_g)⁻¹ ((1 + β ĨI_f)[−ω_y; ω_x] − ĨI_f [v_x; v_y]).
/// Valid for facing normals (σ = −1); used as a cross-check. @pre n_f·n_g < −1 + 1e-9
/// (checked). @return false when singular or when the normals do not face each other.
inline constexpr double kMontanaFacingTolerance = 1e-9;  // |n_f·n_g + 1| at an extremum: rounding
bool ContactJacobianMontana(const SurfacePairEval& e, const BodyPose& pose_f,
                            const BodyPose& pose_g, Matrix4x14* u_q);

/// World contact points and signed distance as functions of q, through u(q):
///   f_q = ∂f/∂q|_u + [f_u f_v] u_q(0:2, :),  g_q likewise,  β_q = n_gᵀ (f_q − g_q).
/// The last is (f − g)ᵀ(f_q − g_q)/β for β ≠ 0 and its limit at β = 0 (d = β n_g at an extremum
/// and n_g·∂n_g = 0), so it is well defined for touching surfaces.
void PointAndDistanceJacobians(const SurfacePairEval& e, const BodyPose& pose_f,
                               const BodyPose& pose_g, const Matrix4x14& u_q, Matrix3x14* f_q,
                               Matrix3x14* g_q, Row14* beta_q);

/// Curve–surface (3 unknowns (u, v, τ)): implicit-function form and the closed form
///   [E_f + β F_f   −P g';  T_xyᵀ F_f   z_f·g''/|g'|] [u̇_f; τ̇] = [v_xy; T_x ω_y − T_y ω_x]
/// (seed 001 Eq. 22–24 rederived in f's frame; T = g'/|g'|, (v, ω) as above at the curve point).
bool CurveSurfaceJacobianImplicit(const CurveSurfaceEval& e, const BodyPose& pose_f,
                                  const BodyPose& pose_g, Matrix3x14* u_q);
bool CurveSurfaceJacobianClosedForm(const CurveSurfaceEval& e, const BodyPose& pose_f,
                                    const BodyPose& pose_g, Matrix3x14* u_q);

}  // namespace tangent::contact
