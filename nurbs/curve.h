#pragma once

#include <vector>

#include <Eigen/Core>

#include "nurbs/knot_vector.h"
#include "nurbs/point_types.h"
#include "nurbs/span_form.h"

namespace tangent::nurbs {

/// A rational B-spline (NURBS) curve of degree 1..9 in `Dim` = 2 (trimming loops in a
/// parameter domain) or 3 (space curves) dimensions, stored with homogeneous control points
/// (w·P, w). Immutable; `Evaluate` (the fast per-span path, as for surfaces) is the default.
template <int Dim>
class NurbsCurve {
 public:
  using Vec = Eigen::Matrix<double, Dim, 1>;
  using HPoint = Eigen::Matrix<double, Dim + 1, 1>;

  /// @param weights empty (non-rational) or one positive finite weight per point.
  /// @throws std::invalid_argument naming the offending count, point or weight.
  NurbsCurve(KnotVector knots, const std::vector<Vec>& points,
             const std::vector<double>& weights = {});
  static NurbsCurve FromHomogeneous(KnotVector knots, std::vector<HPoint> weighted_points);

  int degree() const { return knots_.degree(); }
  int num_points() const { return knots_.num_basis(); }
  const KnotVector& knots() const { return knots_; }
  const std::vector<HPoint>& weighted_points() const { return cpw_; }
  Vec point(int i) const {
    const HPoint& h = cpw_[static_cast<size_t>(i)];
    return h.template head<Dim>() / h[Dim];
  }
  double weight(int i) const { return cpw_[static_cast<size_t>(i)][Dim]; }

  /// Fast path: C and its derivatives up to `order` at t (clamped to the domain). Allocation
  /// free; `hint` is the span of the previous call (any value is valid).
  void Evaluate(double t, int order, int* hint, CurvePoint<Dim>* out) const {
    HomogeneousCurveDerivs<Dim> h;
    fast_.Evaluate(t, order, hint, &h);
    RationalQuotient(h, order, out);
  }
  CurvePoint<Dim> Evaluate(double t, int order = kMaxOrder) const {
    int hint = 0;
    CurvePoint<Dim> out;
    Evaluate(t, order, &hint, &out);
    return out;
  }

 private:
  NurbsCurve(KnotVector knots, std::vector<HPoint> cpw, int);
  void Finish();

  KnotVector knots_;
  std::vector<HPoint> cpw_;
  SpanFormCurve<Dim> fast_;
};

using NurbsCurve2d = NurbsCurve<2>;
using NurbsCurve3d = NurbsCurve<3>;

/// Reference path for curves: basis-function derivatives and the quotient rule.
template <int Dim>
CurvePoint<Dim> EvaluateReference(const NurbsCurve<Dim>& curve, double t, int order = kMaxOrder);

}  // namespace tangent::nurbs
