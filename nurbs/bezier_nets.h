#pragma once

// Bézier nets of B-spline pieces and their derivatives from Oslo blossoms, and the span forms
// built from them. Internal to nurbs/: below surface.h and curve.h (it takes knot vectors and
// homogeneous control nets, not the classes), so the classes build their span form without
// depending on refinement.h, which depends on them.

#include <array>
#include <vector>

#include <Eigen/Core>

#include "nurbs/basis.h"
#include "nurbs/knot_vector.h"
#include "nurbs/span_form.h"

namespace tangent::nurbs::internal {

using AlphaRow = std::array<double, kMaxDegree + 1>;

/// Bezier net of the a-th derivative of the piece on span mu over [t_mu, t_mu+1]: point i is
/// p!/(p−a)! · b(t_mu^{p−a−i}, t_mu+1^i, δ^a); a = 0 gives the span's Bezier net, i = 0..p−a.
void DerivativeBezierRows(const KnotVector& k, int mu, int a, AlphaRow* rows);

/// Non-empty spans of the domain, as knot indices mu.
std::vector<int> DomainSpans(const KnotVector& k);

/// Bezier net of the order-d derivative of a curve's piece on span mu (d = 0: the piece
/// itself): point a = Σ_k alpha_a[k] P_{mu-p+k}, a = 0..p−d.
template <class HPoint>
void CurveBezierNet(const KnotVector& k, const std::vector<HPoint>& pw, int mu, int d,
                    HPoint* net) {
  const int p = k.degree();
  AlphaRow rows[kMaxDegree + 1];
  DerivativeBezierRows(k, mu, d, rows);
  for (int a = 0; a <= p - d; ++a) {
    net[a].setZero();
    for (int i = 0; i <= p; ++i) {
      net[a] += rows[a][static_cast<size_t>(i)] * pw[static_cast<size_t>(mu - p + i)];
    }
  }
}

/// Bezier net of ∂^{du+dv}A/∂u^du ∂v^dv on surface span (mu_u, mu_v) ((0, 0): the patch
/// itself), (p+1−du) x (q+1−dv) points row-major in u, each multiplied by `scale`. `cpw`: the
/// homogeneous net, row-major in u (index i · num_v + j).
void SurfaceBezierNet(const KnotVector& ku, const KnotVector& kv,
                      const std::vector<Eigen::Vector4d>& cpw, int mu_u, int mu_v, int du, int dv,
                      double scale, Eigen::Vector4d* net);

/// Span form of every surface span (Bezier nets of A and its partials), all homogeneous
/// coordinates multiplied by `scale`.
SpanFormSurface BuildSpanForm(const KnotVector& ku, const KnotVector& kv,
                              const std::vector<Eigen::Vector4d>& cpw, double scale = 1.0);
/// Span form of every curve span (Bezier nets of C, C', C'').
template <int Dim>
SpanFormCurve<Dim> BuildSpanForm(const KnotVector& k,
                                 const std::vector<Eigen::Matrix<double, Dim + 1, 1>>& cpw);

}  // namespace tangent::nurbs::internal
