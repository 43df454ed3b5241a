#pragma once

// Edge against edge (issue 34, seed 001's third trimming constraint): the extremal distance
// between two curves on two bodies, each a trim edge of a face mapped through its surface
// (BodyCurve), a(s) on body A and b(t) on body B. docs/trimming.md, "Edge against edge", has
// the mathematics. The solver, its closed-form Jacobian, and the distance's and the signed
// row's gradient and Hessian in the poses; contact/trimmed.h follows such contacts.

#include <Eigen/Core>
#include <array>

#include "contact/contact_jacobian.h"
#include "contact/extremal.h"
#include "contact/placed.h"

namespace tangent::contact {

using Matrix2x14 = Eigen::Matrix<double, 2, 14>;
using Matrix14d = Eigen::Matrix<double, 14, 14>;

/// The pair at (s, t): both curve points to second order, d = a − b, and the gradient and
/// Hessian of ½|d|² in (s, t):
///   grad = [d·a', −d·b'],  hess = [a'·a' + d·a'', −a'·b'; −a'·b', b'·b' − d·b''].
/// Unlike a surface pair's, this system stays regular where the edges touch (d = 0): its
/// determinant is then |a'|²|b'|² − (a'·b')² = |a' × b'|², zero only for parallel edges.
struct CurveCurveEval {
  PlacedCurvePoint a, b;
  Eigen::Vector3d d = Eigen::Vector3d::Zero();  ///< a − b, world
  Eigen::Vector2d grad = Eigen::Vector2d::Zero();
  Eigen::Matrix2d hess = Eigen::Matrix2d::Zero();
};
void EvaluateCurveCurve(const BodyCurve& a, const BodyPose& pose_a, const BodyCurve& b,
                        const BodyPose& pose_b, const Eigen::Vector2d& x, int* span_a,
                        nurbs::SpanHint* hint_a, int* span_b, nurbs::SpanHint* hint_b,
                        CurveCurveEval* out);

struct CurveCurveExtremum {
  Eigen::Vector2d x = Eigen::Vector2d::Zero();  ///< (s, t)
  double distance = 0.0;  ///< |a − b| (unsigned: the caller's faces sign it)
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
  ExtremalStatus status = ExtremalStatus::kNotConverged;
  ExtremumKind kind = ExtremumKind::kDegenerate;
  std::array<bool, 2> at_bound{};  ///< a parameter held at its curve's end
  int iterations = 0;
};

/// The minimum of |a(s) − b(t)| from a seed: Newton on the gradient, and where that does not
/// end at a minimum, the bound-constrained minimization from the seed and a Newton polish
/// (contact/box_newton.h). A periodic curve (a closed loop) wraps round. Allocation free.
CurveCurveExtremum SolveCurveCurve(const BodyCurve& a, const BodyPose& pose_a, const BodyCurve& b,
                                   const BodyPose& pose_b, const Eigen::Vector2d& seed,
                                   const ExtremalOptions& options = {},
                                   CurveCurveEval* at_solution = nullptr);

/// How the extremal parameters move with the poses (columns: body A's 7 coordinates, then B's):
/// x_q = −hess⁻¹ ∂grad/∂q, where at fixed (s, t)
///   ∂(d·a')/∂q = a'ᵀ ∂d/∂q + dᵀ ∂a'/∂q,  ∂(−d·b')/∂q = −b'ᵀ ∂d/∂q − dᵀ ∂b'/∂q,
/// ∂d/∂q = [∂a/∂q_A, −∂b/∂q_B] (PointJacobian), ∂a'/∂q_A = DirectionJacobian(A, a'_B). For an
/// extremum with both parameters free; false when hess is singular (parallel edges).
bool CurveCurveJacobian(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                        Matrix2x14* x_q);

/// ∂|d|/∂q along the extremum: n·∂d/∂q at fixed (s, t), n = d/|d| (the parameters' own motion
/// does not change |d| to first order: d ⊥ a', b' there). @pre |d| > 0.
Row14 CurveCurveDistanceGradient(const CurveCurveEval& e, const BodyPose& pose_a,
                                 const BodyPose& pose_b);

/// ∂²|d|/∂q² along the extremum, x_q from CurveCurveJacobian:
///   D = ∂d/∂q + [a' −b'] x_q (the total derivative of d),  ∂n/∂q = (I − n nᵀ) D / |d|,
///   H = (∂d/∂q)ᵀ ∂n/∂q + n·∂²d/∂q² + (nᵀ ∂²d/∂q∂s)ᵀ x_q,s + (nᵀ ∂²d/∂q∂t)ᵀ x_q,t,
/// with n·∂²d/∂q² the rotations' curvature of each body's point (RotateHessian) and
/// ∂²d/∂q∂s = [∂a'/∂q_A, 0], ∂²d/∂q∂t = [0, −∂b'/∂q_B]. @pre |d| > 0.
Matrix14d CurveCurveDistanceHessian(const CurveCurveEval& e, const BodyPose& pose_a,
                                    const BodyPose& pose_b, const Matrix2x14& x_q);

/// The signed edge–edge row (docs/trimming.md, "Edge against edge"). At an extremum where both
/// parameters are free, d ⟂ a' and d ⟂ b', so d lies along the edges' common normal
/// ν = σ (a' × b')/|a' × b'|, and β = d·ν is the signed distance: smooth through touching (d = 0),
/// where |d| is not. σ = ±1 is the contact's side, chosen where it starts (ν from g's edge
/// towards f's where they are apart) and kept while it is followed.
///   ∇β = ν·∂d/∂q at fixed (s, t) (ν ⟂ a', b' everywhere and d ⟂ ∂ν at the extremum),
///   ∇²β = (∂d/∂q)ᵀ ∂ν/∂q + ν·∂²d/∂q² + (νᵀ ∂a'/∂q)ᵀ x_q,s − (νᵀ ∂b'/∂q)ᵀ x_q,t,
///   ∂ν/∂q = (I − ννᵀ)(Ȧ' × b' + a' × Ḃ')/|a' × b'|,  Ȧ' = ∂a'/∂q + a'' x_q,s,  Ḃ' likewise.
/// False (ν unset) where the edges are parallel to 1e-9 (|a' × b'| ≤ 1e-9 |a'||b'|).
bool CommonNormal(const CurveCurveEval& e, double sign, Eigen::Vector3d* nu);
Row14 EdgeEdgeGradient(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                       const Eigen::Vector3d& nu);
/// ∇²β as above, the rotations' curvature of each point included. x_q from CurveCurveJacobian.
Matrix14d EdgeEdgeHessian(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                          const Matrix2x14& x_q, const Eigen::Vector3d& nu);

}  // namespace tangent::contact
