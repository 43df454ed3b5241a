#pragma once

// The relative curvature of two surfaces at an extremal pair: whether the pair is a true
// contact (the surfaces lie on either side of the common tangent plane near it) or a saddle of
// the distance (the surfaces cross near it, so a constraint β ≥ 0 there lets them
// interpenetrate a little way off). docs/contact.md, "Saddles and contact splitting".

#include <Eigen/Core>

#include "contact/extremal.h"

namespace tangent::contact {

/// The shape operator of a placed surface point as a symmetric 3 x 3 world matrix on its
/// tangent plane, signed so that a surface convex toward its outward normal is positive:
///   K_W = −T I⁻¹ II I⁻¹ Tᵀ,  T = [S_u S_v] (world), I = TᵀT, II_ij = S_ij·n (n = N/|N|),
/// so the normal curvature along a unit tangent t is tᵀ K_W t (Meusnier: the normal component
/// of the acceleration of any surface curve with unit speed along t, negated). Units 1/m.
/// @return false at a pole (T singular: the shape operator is not defined by the chart there);
/// *K_W is then left zero.
bool ShapeOperator(const PlacedSurfacePoint& p, Eigen::Matrix3d* K_W);

/// The relative curvature of a facing pair at an extremum at signed distance β = d·n_g: with a
/// unit tangent frame (x, y) of g, f touches g offset by β (whose shape operator is
/// K_g (1 + β K_g)⁻¹), and the gap between f and that offset along n_g at a tangent offset ξ
/// from the contact is, to second order,
///   gap(ξ) = ½ ξᵀ M ξ,   M = [x y]ᵀ (K_f + K_g (1 + β K_g)⁻¹) [x y],
/// both shape operators convex-positive toward their own outward normals (which face each
/// other: n_f = −n_g). M positive semidefinite: the pair is a minimum of the distance (a point
/// contact when definite, a line contact when singular). M indefinite: a saddle; the surfaces
/// (at β = 0) cross near the point along the eigenvector of the negative eigenvalue, and two
/// minima lie on either side of it along that direction.
struct RelativeCurvature {
  /// false at a pole of either surface, with normals not facing, or at a focal distance
  /// (1 + β K_g singular)
  bool valid = false;
  Eigen::Vector2d eigenvalues;    ///< of M, ascending (1/m)
  Eigen::Vector3d min_direction;  ///< unit world tangent of the smaller eigenvalue
  /// The saddle test: λ_min < −kCrossingTolerance · max|λ|. Relative, since M's entries carry
  /// the rounding of second derivatives (~1e-10 relative from the span forms) and a saddle that
  /// shallow dips by ½|λ|ξ² ≈ 1e-6 of the curvature scale at ξ = one radius: nothing to hold.
  bool crossing = false;
};
inline constexpr double kCrossingTolerance = 1e-6;

/// Relative curvature of the pair in `e` (f's and g's points and second derivatives, world).
RelativeCurvature RelativeCurvatureOf(const SurfacePairEval& e);

/// The parameter step (Δu, Δv, Δs, Δt) that moves both contact points by the world tangent
/// vector w (least squares on each surface's tangent plane: Δ = (TᵀT)⁻¹Tᵀw). Used to seed the
/// minima on either side of a saddle. @pre neither point is a pole.
Eigen::Vector4d ParameterStepAlong(const SurfacePairEval& e, const Eigen::Vector3d& w);

/// The minimum beside a saddle on one side (`side` ±1 along rc.min_direction): Newton from a
/// seed beside the saddle is drawn back to it (the nearest critical point), so f's point first
/// walks along the crossing direction, in steps growing from 1 % of the curvature radius
/// 1/max|λ| up to two radii, while its distance to g (a point–surface solve) keeps falling;
/// Newton from the lowest point then lands in the minimum's basin. @return whether that Newton
/// converged to a facing minimum (not itself crossing): *out and *out_eval. Allocation free.
/// The global stage's split (MinimaBeside) and a split row's return to its own minimum
/// (optimizer/split_rows.h) both take it.
bool MinimumBesideSaddle(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                         const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                         const SurfaceSurfaceExtremum& saddle, const SurfacePairEval& at,
                         const RelativeCurvature& rc, double side, SurfaceSurfaceExtremum* out,
                         SurfacePairEval* out_eval);

}  // namespace tangent::contact
