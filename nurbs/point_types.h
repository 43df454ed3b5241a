#pragma once

#include <Eigen/Core>

#include "nurbs/basis.h"

namespace tangent::nurbs {

/// Range of control-point coordinates and weights that NURBS constructors accept. Evaluation
/// forms weighted points w·P, sums of up to 100 of them, derivatives that multiply by up to
/// (1/h)² on short spans (1e18 at h = 1e-9) and squares of those (normals, distances): with
/// |P|, w and w·|P| within 1e100 (and w ≥ 1e-100) none of these overflow a double (1e308).
/// Weights like 1e300 used to pass validation and overflow to NaN on evaluation.
inline constexpr double kMaxCoordinate = 1e100;
inline constexpr double kMinWeight = 1e-100;
inline constexpr double kMaxWeight = 1e100;

/// A surface point and its partial derivatives, all in the surface's own frame (for a surface
/// mounted on a body: the body frame B). Entries beyond the requested order are left unset.
struct SurfacePoint {
  Eigen::Vector3d S;     ///< S(u, v)
  Eigen::Vector3d S_u;   ///< ∂S/∂u
  Eigen::Vector3d S_v;   ///< ∂S/∂v
  Eigen::Vector3d S_uu;  ///< ∂²S/∂u²
  Eigen::Vector3d S_uv;  ///< ∂²S/∂u∂v
  Eigen::Vector3d S_vv;  ///< ∂²S/∂v²
};

/// A curve point in `Dim` dimensions and its first two derivatives with respect to the parameter.
template <int Dim>
struct CurvePoint {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  Vec C;   ///< C(t)
  Vec C1;  ///< C'(t)
  Vec C2;  ///< C''(t)
};

/// Derivatives of the homogeneous (weighted) surface A(u,v) = (w·S, w), in the order
/// A, A_u, A_v, A_uu, A_uv, A_vv.
struct HomogeneousSurfaceDerivs {
  Eigen::Vector4d A[6];
};

/// Derivatives A, A', A'' of a homogeneous curve (w·C, w) with `Dim + 1` components.
template <int Dim>
struct HomogeneousCurveDerivs {
  Eigen::Matrix<double, Dim + 1, 1> A[3];
};

/// The quotient rule: Cartesian derivatives of S = A_xyz / w up to `order`.
/// S_u = (A_u − w_u S)/w,  S_uu = (A_uu − 2 w_u S_u − w_uu S)/w,
/// S_uv = (A_uv − w_u S_v − w_v S_u − w_uv S)/w  (and symmetrically in v).
inline void RationalQuotient(const HomogeneousSurfaceDerivs& h, int order, SurfacePoint* out) {
  const double inv_w = 1.0 / h.A[0][3];
  out->S = h.A[0].head<3>() * inv_w;
  if (order < 1) return;
  const double w_u = h.A[1][3];
  const double w_v = h.A[2][3];
  out->S_u = (h.A[1].head<3>() - w_u * out->S) * inv_w;
  out->S_v = (h.A[2].head<3>() - w_v * out->S) * inv_w;
  if (order < 2) return;
  out->S_uu = (h.A[3].head<3>() - 2.0 * w_u * out->S_u - h.A[3][3] * out->S) * inv_w;
  out->S_uv = (h.A[4].head<3>() - w_u * out->S_v - w_v * out->S_u - h.A[4][3] * out->S) * inv_w;
  out->S_vv = (h.A[5].head<3>() - 2.0 * w_v * out->S_v - h.A[5][3] * out->S) * inv_w;
}

/// For a polynomial (non-rational) surface stored with w ≡ 1: S and its partials are the first
/// three components, with no quotient.
inline void PolynomialPart(const HomogeneousSurfaceDerivs& h, int order, SurfacePoint* out) {
  out->S = h.A[0].head<3>();
  if (order < 1) return;
  out->S_u = h.A[1].head<3>();
  out->S_v = h.A[2].head<3>();
  if (order < 2) return;
  out->S_uu = h.A[3].head<3>();
  out->S_uv = h.A[4].head<3>();
  out->S_vv = h.A[5].head<3>();
}

/// The quotient rule for curves: C = A/w, C' = (A' − w'C)/w, C'' = (A'' − 2w'C' − w''C)/w.
template <int Dim>
inline void RationalQuotient(const HomogeneousCurveDerivs<Dim>& h, int order,
                             CurvePoint<Dim>* out) {
  const double inv_w = 1.0 / h.A[0][Dim];
  out->C = h.A[0].template head<Dim>() * inv_w;
  if (order < 1) return;
  const double w1 = h.A[1][Dim];
  out->C1 = (h.A[1].template head<Dim>() - w1 * out->C) * inv_w;
  if (order < 2) return;
  out->C2 = (h.A[2].template head<Dim>() - 2.0 * w1 * out->C1 - h.A[2][Dim] * out->C) * inv_w;
}

}  // namespace tangent::nurbs
