#pragma once

#include <array>
#include <utility>
#include <vector>

#include "nurbs/curve.h"
#include "nurbs/knot_vector.h"
#include "nurbs/surface.h"

namespace tangent::nurbs {

/// The discrete B-spline (alpha) matrix of a knot refinement τ → t (Oslo algorithm):
/// new coefficient j = Σ_k alpha[j][k] · old coefficient (first[j] + k), k = 0..p.
struct AlphaMatrix {
  int degree = 0;
  std::vector<int> first;
  std::vector<std::array<double, kMaxDegree + 1>> alpha;
};

/// Oslo algorithm: the alpha matrix taking coefficients on `old_knots` to `refined`.
/// @throws std::invalid_argument unless `refined` has the same degree and domain and contains
///   every interior knot of `old_knots` with at least its multiplicity.
AlphaMatrix OsloAlphaMatrix(const KnotVector& old_knots, const KnotVector& refined);

/// Parameter direction of a surface.
enum class Direction { kU, kV };

/// Knot refinement by the Oslo algorithm; the geometry is unchanged.
template <int Dim>
NurbsCurve<Dim> RefineKnots(const NurbsCurve<Dim>& curve, const KnotVector& refined);
NurbsSurface RefineKnots(const NurbsSurface& surface, Direction dir, const KnotVector& refined);

/// Single knot insertion `times` times (Boehm's algorithm, Piegl & Tiller A5.1). An independent
/// implementation, kept to cross-check the Oslo algorithm.
/// @throws std::invalid_argument when t is outside the domain or the multiplicity would exceed p.
template <int Dim>
NurbsCurve<Dim> InsertKnot(const NurbsCurve<Dim>& curve, double t, int times = 1);
NurbsSurface InsertKnot(const NurbsSurface& surface, Direction dir, double t, int times = 1);

/// The Bezier pieces of a curve, one per non-empty span, each clamped on its span.
template <int Dim>
std::vector<NurbsCurve<Dim>> ExtractBezier(const NurbsCurve<Dim>& curve);
/// The Bezier patches of a surface, row-major over spans (u-span index · spans_v + v-span).
std::vector<NurbsSurface> ExtractBezier(const NurbsSurface& surface);

/// Splits at an interior parameter into two clamped pieces meeting at t.
/// @throws std::invalid_argument when t is not strictly inside the domain.
template <int Dim>
std::pair<NurbsCurve<Dim>, NurbsCurve<Dim>> Split(const NurbsCurve<Dim>& curve, double t);
std::pair<NurbsSurface, NurbsSurface> Split(const NurbsSurface& surface, Direction dir, double t);

/// Refinement path of evaluation (seed 001 §2.2, Alpha_1 style): the parameter t is inserted to
/// full multiplicity p by the Oslo algorithm, together with the span end e, which makes the span a
/// Bezier segment [t, e] whose first refined control points give A = Q0, A' = p (Q1 − Q0)/h,
/// A'' = p(p−1)(Q2 − 2Q1 + Q0)/h², h = e − t; the quotient rule handles weights. The differences
/// are formed on the alpha rows through the blossom's multi-affinity,
/// Q1 − Q0 = b(t^{p−1}, e) − b(t^{p−1}, t) = h·b(t^{p−1}, δ), so no rounded control points are
/// subtracted and the result does not lose digits when t is close to a knot. Only the refined
/// control points that are read are computed.
SurfacePoint EvaluateByRefinement(const NurbsSurface& surface, double u, double v,
                                  int order = kMaxOrder);
template <int Dim>
CurvePoint<Dim> EvaluateByRefinement(const NurbsCurve<Dim>& curve, double t, int order = kMaxOrder);

}  // namespace tangent::nurbs
