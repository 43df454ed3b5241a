#pragma once

#include <array>

#include "nurbs/knot_vector.h"

namespace tangent::nurbs {

/// Highest derivative order any evaluator returns (what contact Jacobians need).
inline constexpr int kMaxOrder = 2;

/// `ders[k][j]` is the k-th derivative of basis function N_{span-p+j, p} at t.
using BasisTable = std::array<std::array<double, kMaxDegree + 1>, kMaxOrder + 1>;

/// The `p + 1` non-zero B-spline basis functions at `t` and their derivatives up to `order`
/// (Cox–de Boor with the derivative recurrence, Piegl & Tiller A2.3). No allocation.
/// @pre `span == knots.FindSpan(t)`, `0 <= order <= kMaxOrder`.
void BasisDerivatives(const KnotVector& knots, int span, double t, int order, BasisTable* ders);

/// One row of the Oslo algorithm's alpha matrix (discrete B-splines): the weights `alpha[0..p]`
/// on the old coefficients `c_{mu-p} .. c_mu` that give the blossom of the polynomial piece on
/// span `mu` at the `p` arguments `x[0..p-1]`. A refined coefficient c'_j is this row with
/// `x = (t'_{j+1}, ..., t'_{j+p})` and `mu` the old span holding `t'_j` (Lyche & Mørken,
/// Oslo algorithm 2); with all `x` equal to `t` the row is the basis functions at `t`.
/// @pre `knots[mu] < knots[mu + 1]`; every `x` lies in the span's support so denominators are > 0.
/// `num_delta` of the arguments (the last ones) may be replaced by the unit direction δ of the
/// blossom's linear part: by multi-affinity, b(x.., t + h) − b(x.., t) = h · b(x.., δ), so a
/// difference of refined control points divided by the knot gap is formed without cancellation.
void OsloAlphaRow(const KnotVector& knots, int mu, const double* x,
                  std::array<double, kMaxDegree + 1>* alpha, int num_delta = 0);

}  // namespace tangent::nurbs
