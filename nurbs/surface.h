#pragma once

#include <vector>

#include <Eigen/Core>

#include "nurbs/knot_vector.h"
#include "nurbs/point_types.h"
#include "nurbs/span_form.h"

namespace tangent::nurbs {

/// A rational tensor-product B-spline (NURBS) surface of degree (p, q), 1 ≤ p, q ≤ 9,
/// S(u,v) = Σ N_i(u) M_j(v) w_ij P_ij / Σ N_i(u) M_j(v) w_ij, in its own frame.
/// Control points are stored homogeneous, P^w_ij = (w_ij P_ij, w_ij), row-major in u:
/// index `i * num_v() + j`. Immutable; construction validates the input and precomputes the
/// per-span form (SpanFormSurface) that `Evaluate` (the fast path, the default) uses.
class NurbsSurface {
 public:
  /// @param points `num_u * num_v` Cartesian control points (index i·num_v + j), metres.
  /// @param weights empty (non-rational) or one positive finite weight per control point.
  /// @throws std::invalid_argument naming the offending knot, point or weight.
  NurbsSurface(KnotVector knots_u, KnotVector knots_v, const std::vector<Eigen::Vector3d>& points,
               const std::vector<double>& weights = {});
  /// Same, from homogeneous points (w·P, w).
  static NurbsSurface FromHomogeneous(KnotVector knots_u, KnotVector knots_v,
                                      std::vector<Eigen::Vector4d> weighted_points);

  int degree_u() const { return knots_u_.degree(); }
  int degree_v() const { return knots_v_.degree(); }
  int num_u() const { return knots_u_.num_basis(); }
  int num_v() const { return knots_v_.num_basis(); }
  const KnotVector& knots_u() const { return knots_u_; }
  const KnotVector& knots_v() const { return knots_v_; }
  const std::vector<Eigen::Vector4d>& weighted_points() const { return cpw_; }
  const Eigen::Vector4d& weighted_point(int i, int j) const {
    return cpw_[static_cast<size_t>(i * num_v() + j)];
  }
  Eigen::Vector3d point(int i, int j) const {
    const Eigen::Vector4d& h = weighted_point(i, j);
    return h.head<3>() / h[3];
  }
  double weight(int i, int j) const { return weighted_point(i, j)[3]; }
  /// False when all weights are equal (then the quotient is a constant and S is polynomial).
  bool IsRational() const { return rational_; }
  /// Closed with continuous first derivatives across the seam (S and S_u at u = begin equal
  /// those at u = end, sampled along v): the parameter may wrap around (a sphere's longitude,
  /// the angle around a tube). Periodic in v likewise.
  bool periodic_u() const { return periodic_u_; }
  bool periodic_v() const { return periodic_v_; }
  const SpanFormSurface& span_form() const { return fast_; }

  /// Fast path: S and its partials up to `Order` at (u, v) clamped to the domain. Allocation
  /// free; `hint` carries span coherence between calls (one per caller).
  template <int Order>
  void Evaluate(double u, double v, SpanHint* hint, SurfacePoint* out) const {
    HomogeneousSurfaceDerivs h;
    fast_.Evaluate<Order>(u, v, hint, &h);
    if (rational_) {
      RationalQuotient(h, Order, out);
    } else {
      PolynomialPart(h, Order, out);  // The span form was built with w ≡ 1: no quotient.
    }
  }
  /// Convenience form of the fast path (order 0..2) without coherence.
  SurfacePoint Evaluate(double u, double v, int order = kMaxOrder) const;

 private:
  NurbsSurface(KnotVector knots_u, KnotVector knots_v, std::vector<Eigen::Vector4d> cpw, int);
  void Finish();

  KnotVector knots_u_;
  KnotVector knots_v_;
  std::vector<Eigen::Vector4d> cpw_;
  bool rational_ = false;
  bool periodic_u_ = false, periodic_v_ = false;
  SpanFormSurface fast_;
};

/// Reference path: basis functions and their derivatives (Piegl & Tiller A2.3) contracted with
/// the homogeneous net, then the rational quotient rule. Slow and simple; the ground truth the
/// other paths are tested against. (u, v) is clamped to the domain.
SurfacePoint EvaluateReference(const NurbsSurface& surface, double u, double v,
                               int order = kMaxOrder);

/// Relative size below which a first partial counts as vanished: |S_u| ≤ kDegenerateRatio |S_v|
/// (or the reverse) is a degenerate point such as a sphere's pole. There N = S_u × S_v has lost
/// all but ~eps/1e-8 of its direction, while the limit normal below is exact to O(1e-8).
inline constexpr double kDegenerateRatio = 1e-8;

/// Whether p (first partials) is a degenerate point of the parameterization (a pole, a
/// collapsed edge): one partial vanishes against the other, or both vanish.
bool IsDegenerate(const SurfacePoint& p);

/// The unit normal N/|N| at (u, v), p = the surface there to second order. At a degenerate point
/// the limit of the normals from inside the domain: where S_u vanishes along a row v = v₀,
/// N(u, v₀ + δ) = δ (S_uv × S_v) + O(δ²), so the normal is ±S_uv × S_v with the sign of the
/// inward δ (+ at the lower v bound, − at the upper); likewise ±S_u × S_uv where S_v vanishes.
/// On a sphere or any surface of revolution this is the axis direction at the pole, the same for
/// every u. If that too vanishes (a higher-order or corner collapse) the normal is taken 1e-7 of
/// the domain inward in both directions. Allocation free.
Eigen::Vector3d UnitNormal(const NurbsSurface& surface, double u, double v, const SurfacePoint& p);

}  // namespace tangent::nurbs
