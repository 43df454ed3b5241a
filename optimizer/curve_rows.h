#pragma once

// One inequality row measured between a curve on body a and a surface g on body b at their
// curve–surface extremum (contact::SolveCurveSurface): a trim edge's row (TrimmedContactTerm on
// the edge) and a line contact's section row (SectionContactTerm) share it. With E the curve's
// point, G = g(s, t) and n the direction β is measured along (g's unit normal at an interior
// extremum, ±(E − G)/|E − G| where it is held on a bound):
//   β = (E − G)·n,   ∇β = n·(∂E/∂q − ∂G/∂q) at fixed parameters (they are stationary),
//   ∇²β = Pᵀ n_q + n·∂²(E − G)/∂q² + V_Eᵀ τ_q − V_Gᵀ (s, t)_q,
// P = ∂(E − G)/∂q at fixed parameters, n_q the normal's total derivative (body b's rotation and
// (s, t)), V the normal component of P's change with the parameters and (s, t, τ)_q the
// curve–surface contact Jacobian (contact::CurveSurfaceJacobianImplicit). Held on a bound the
// Hessian is left to the solver's Gauss–Newton model.

#include <Eigen/Core>

#include "contact/extremal.h"
#include "contact/placed.h"
#include "optimizer/term.h"

namespace tangent::optimizer::internal {

/// The direction β is measured along at extremum x (its evaluation e: e.f is g, e.g the curve).
Eigen::Vector3d CurveRowDirection(const contact::CurveSurfaceExtremum& x);
/// r = β, J_a = n·∂E/∂q_a, J_b = −n·∂G/∂q_b.
void CurveRowJacobian(const contact::CurveSurfaceEval& e, const Eigen::Vector3d& n,
                      const contact::BodyPose& pa, const contact::BodyPose& pb,
                      Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b);
/// Adds w ∇²β into *h (nothing when x is held on a bound).
void AddCurveRowHessian(const contact::CurveSurfaceEval& e, const contact::CurveSurfaceExtremum& x,
                        const Eigen::Vector3d& n, const contact::BodyPose& pa,
                        const contact::BodyPose& pb, double w, TermHessian* h);

/// A curve's curvature |C' × C''| / |C'|³ at a point; false where C' = 0.
bool CurveCurvature(const nurbs::CurvePoint<3>& c, double* kappa);

/// The row's reach (Term::Reach): its gap plus a quarter of the curve's radius of curvature
/// |C'|³ / |C' × C''| at E (the tighter of the two where a curve meets a surface across it).
bool CurveRowReach(const contact::CurveSurfaceEval& e, const contact::CurveSurfaceExtremum& x,
                   Eigen::Vector3d* p, double* reach);

}  // namespace tangent::optimizer::internal
