#pragma once

#include <Eigen/Core>

#include "contact/rigid.h"
#include "nurbs/curve.h"
#include "nurbs/surface.h"

namespace tangent::contact {

/// A pose with its rotation computed once: what every placed evaluation needs.
struct BodyPose {
  Vector7d q;                             ///< the body's coordinates [p_WB, Q_WB]
  Eigen::Matrix3d R_WB;                   ///< rotation body → world: R(Q/|Q|)
  Eigen::Matrix<double, 3, 4> omega_map;  ///< w_W = omega_map · Q̇ (exact for the normalized map)

  static BodyPose FromCoordinates(const Vector7d& q);
  /// World position of a body-fixed point: p_WB + R_WB p_BQ.
  Eigen::Vector3d Point(const Eigen::Vector3d& p_B) const { return q.head<3>() + R_WB * p_B; }
};

/// A surface point on a body: body-frame evaluation and its world image, S(u,v) and partials.
struct PlacedSurfacePoint {
  nurbs::SurfacePoint body;   ///< in the body frame B
  nurbs::SurfacePoint world;  ///< in the world frame W (points moved, partials rotated)
  Eigen::Vector3d N_W;        ///< S_u × S_v in W (unnormalized normal; 0 at a pole)
  bool pole = false;          ///< a degenerate point of the parameterization (nurbs::IsDegenerate)
  Eigen::Vector3d n_W_limit;  ///< at a pole: the limit unit normal in W (nurbs::UnitNormal)
  /// The partials are in a pole's tangent-plane chart (x, y), not in (u, v) (EvaluateCharted,
  /// contact/pole_chart.h): regular at the pole itself.
  bool charted = false;
  /// Unit outward normal in W: N/|N|, or at a pole the limit normal (computed on demand: most
  /// evaluations inside a solve never need it).
  Eigen::Vector3d unit_normal() const {
    return pole ? n_W_limit : Eigen::Vector3d(N_W.normalized());
  }
  Eigen::Vector3d N_W_u,
      N_W_v;  ///< its partials, S_uu × S_v + S_u × S_uv and S_uv × S_v + S_u × S_vv
};

/// Evaluates a body's surface at (u, v) to second order (fast path, allocation free).
void EvaluatePlaced(const nurbs::NurbsSurface& surface, const BodyPose& pose, double u, double v,
                    nurbs::SpanHint* hint, PlacedSurfacePoint* out);
/// Fills out->world, N_W and its partials from out->body (a point evaluated in the body frame,
/// in whatever coordinates its partials are taken).
void PlaceBody(const BodyPose& pose, PlacedSurfacePoint* out);

/// A curve fixed on a body: either a space curve in the body frame, or a curve c(τ) in the
/// parameter domain of one of the body's surfaces (a trimming loop), g(τ) = S(c(τ)).
class BodyCurve {
 public:
  explicit BodyCurve(const nurbs::NurbsCurve3d* space_curve) : space_(space_curve) {}
  /// `periodic`: the curve is closed with a continuous first derivative across its ends (a
  /// trim loop's circle), so its parameter wraps round instead of stopping at the ends.
  BodyCurve(const nurbs::NurbsSurface* surface, const nurbs::NurbsCurve2d* domain_curve,
            bool periodic = false)
      : surface_(surface), domain_(domain_curve), periodic_(periodic) {}
  /// A parameter line of a surface, g(τ) = S(value, τ) when `fixed` is 0 (u held: the line runs
  /// along v) or S(τ, value) when 1 (v held). Periodic when the surface is in the running
  /// parameter. Allocation free: a line contact's section (docs/contact.md, "Line contacts").
  static BodyCurve Isoline(const nurbs::NurbsSurface* surface, int fixed, double value) {
    BodyCurve c(surface, nullptr, fixed == 0 ? surface->periodic_v() : surface->periodic_u());
    c.iso_fixed_ = fixed;
    c.iso_value_ = value;
    return c;
  }
  /// For an isoline: which parameter is held (0 u, 1 v; −1 not an isoline) and its value.
  int iso_fixed() const { return iso_fixed_; }
  double iso_value() const { return iso_value_; }
  double domain_begin() const;
  double domain_end() const;
  bool periodic() const { return periodic_; }
  /// g, g', g'' in the body frame at τ (chain rule for a curve on a surface).
  nurbs::CurvePoint<3> Evaluate(double tau, int* span_hint, nurbs::SpanHint* surface_hint) const;

 private:
  const nurbs::NurbsCurve3d* space_ = nullptr;
  const nurbs::NurbsSurface* surface_ = nullptr;
  const nurbs::NurbsCurve2d* domain_ = nullptr;
  bool periodic_ = false;
  int iso_fixed_ = -1;
  double iso_value_ = 0.0;
};

/// A curve point on a body, body and world.
struct PlacedCurvePoint {
  nurbs::CurvePoint<3> body{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                            Eigen::Vector3d::Zero()};
  nurbs::CurvePoint<3> world{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                             Eigen::Vector3d::Zero()};
};

void EvaluatePlaced(const BodyCurve& curve, const BodyPose& pose, double tau, int* span_hint,
                    nurbs::SpanHint* surface_hint, PlacedCurvePoint* out);

/// The contact frame of a surface point (seed 001 Appendix A), columns x, y, z in W:
/// x = S_u/|S_u|, z = n (outward normal), y = z × x. At a pole (p.pole) z is the limit normal
/// from inside the domain (nurbs::UnitNormal) and x the surviving partial's direction, made
/// orthogonal to z: a right-handed orthonormal frame everywhere, never NaN.
Eigen::Matrix3d ContactFrame(const PlacedSurfacePoint& p);

/// ∂x_W/∂q_B (3 x 7) of a body-fixed point with body coordinates p_B: [I, ∂(R p_B)/∂Q].
Matrix37d PointJacobian(const BodyPose& pose, const Eigen::Vector3d& p_B);
/// ∂a_W/∂q_B (3 x 7) of a body-fixed direction a_B (a partial, a normal): [0, ∂(R a_B)/∂Q].
Matrix37d DirectionJacobian(const BodyPose& pose, const Eigen::Vector3d& a_B);
/// n·∂a_W/∂Q (1 x 4) of a body-fixed direction or offset whose world image a_W = R a_B is
/// already known: nᵀ DirectionJacobian's rotational columns, (a_W × n)ᵀ omega_map, without the
/// 3 x 4 matrix (15 multiplications against 48).
inline Eigen::RowVector4d DirectionGradient(const BodyPose& pose, const Eigen::Vector3d& a_W,
                                            const Eigen::Vector3d& n) {
  return a_W.cross(n).transpose() * pose.omega_map;
}

}  // namespace tangent::contact
