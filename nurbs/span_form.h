#pragma once

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "nurbs/knot_vector.h"
#include "nurbs/point_types.h"
#include "nurbs/span_kernels.h"

namespace tangent::nurbs {

/// Coherence state for repeated evaluations: the span indices of the previous call. Each caller
/// (e.g. each tracked contact) keeps its own; a default-constructed hint is always valid.
struct SpanHint {
  int u = 0;
  int v = 0;
};

namespace internal {

/// Index i with `breaks[i] <= x < breaks[i+1]`, clamped to [0, breaks.size() - 2]; tries `hint`
/// first, then a branchless binary search.
int FindInterval(const std::vector<double>& breaks, double x, int hint);

/// Bernstein polynomials at s ∈ [0, 1] of degrees p, p−1, p−2: b[d][i] = B_{i,p−d}(s) (rows of
/// negative degree are left untouched), from the de Casteljau triangle.
void BernsteinValues(int p, double s, double b[kMaxOrder + 1][kMaxDegree + 1]);

/// M with power coefficient k = Σ_i M(k, i) b_i for a degree-p Bezier polynomial in s ∈ [0, 1]:
/// M(k, i) = C(p, k) C(k, i) (−1)^(k−i) for i ≤ k, 0 otherwise.
Eigen::MatrixXd BezierToPowerMatrix(int p);

}  // namespace internal

/// The servo-loop evaluator of a rational tensor-product surface: every non-empty knot span
/// (i, j) stores its polynomial piece of the homogeneous surface A = (w·S, w) in the normalized
/// local parameters s = (u − u_i)/h_u, t = (v − v_j)/h_v, so one evaluation is a span lookup
/// (O(1) with a coherent hint) and one small tensor contraction, with no allocation.
/// For degrees ≤ 3 in both directions the piece is kept in the power basis and evaluated by
/// nested, fully unrolled Horner schemes (the fastest form; its Bezier-to-monomial conversion
/// costs at most ~1e-13 relative at degree 3). Above degree 3 the power basis is ill-conditioned
/// (measured: 1e-8 relative error in S_uu at degree 9), so each span keeps the Bezier nets of A
/// and of its five partial derivatives (the hodographs, built from δ-blossoms of the B-spline so
/// no control points are differenced) and evaluates them with Bernstein polynomials, which are
/// well conditioned at every degree.
class SpanFormSurface {
 public:
  SpanFormSurface() = default;
  /// `nets` holds, span after span (row-major over spans (i, j)), the Bezier nets of A_(a,b) =
  /// ∂^{a+b}A/∂u^a∂v^b for (a,b) in kFamilies order, each (p+1−a) x (q+1−b) points row-major
  /// in u (empty when a > p or b > q). For degrees ≤ 3 only the first net (of A) is read; it is
  /// converted to the power basis.
  SpanFormSurface(int p, int q, std::vector<double> breaks_u, std::vector<double> breaks_v,
                  const std::vector<Eigen::Vector4d>& nets);

  /// The derivative orders (a, b) stored per span, in the order of HomogeneousSurfaceDerivs.
  static constexpr int kFamilies[6][2] = {{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
  /// Number of homogeneous points of all nets of one span as the constructor expects them.
  static int NetPointsPerSpan(int p, int q);

  /// Homogeneous derivatives up to `Order` at (u, v), clamped to the domain.
  template <int Order>
  void Evaluate(double u, double v, SpanHint* hint, HomogeneousSurfaceDerivs* out) const {
    static_assert(Order >= 0 && Order <= kMaxOrder);
    const int i = internal::FindInterval(breaks_u_, u, hint->u);
    const int j = internal::FindInterval(breaks_v_, v, hint->v);
    hint->u = i;
    hint->v = j;
    const double u0 = breaks_u_[static_cast<size_t>(i)];
    const double v0 = breaks_v_[static_cast<size_t>(j)];
    const double inv_hu = inv_h_u_[static_cast<size_t>(i)];
    const double inv_hv = inv_h_v_[static_cast<size_t>(j)];
    // Clamp to the span so a parameter outside the domain evaluates the domain edge.
    const double s = std::clamp((u - u0) * inv_hu, 0.0, 1.0);
    const double t = std::clamp((v - v0) * inv_hv, 0.0, 1.0);
    const Eigen::Vector4d* c =
        coeffs_.data() + static_cast<size_t>(i * num_spans_v() + j) * patch_size_;
    if (bicubic_ && !avx2_) {
      internal::SurfaceKernel<3, 3, Order>(c, 3, 3, s, t, inv_hu, inv_hv, out);
    } else {
      kernels_[Order](c, p_, q_, s, t, inv_hu, inv_hv, out);
    }
  }

  /// True when the pieces are held in the power basis (both degrees ≤ 3).
  bool uses_power_basis() const { return power_; }
  int degree_u() const { return p_; }
  int degree_v() const { return q_; }
  int num_spans_u() const { return static_cast<int>(breaks_u_.size()) - 1; }
  int num_spans_v() const { return static_cast<int>(breaks_v_.size()) - 1; }

  using Kernel = internal::SpanKernel;

 private:
  int p_ = 0;
  int q_ = 0;
  bool power_ = false;
  bool bicubic_ = false;   // The common CAD case, dispatched without an indirect call ...
  bool avx2_ = false;      // ... unless the CPU has AVX2 + FMA: then the intrinsics kernel.
  size_t patch_size_ = 0;  // (p+1)(q+1) homogeneous coefficients
  std::vector<double> breaks_u_, breaks_v_, inv_h_u_, inv_h_v_;
  // Per span, C[a][b] at a*(q+1)+b: the coefficient of s^a t^b (power basis) or the Bezier
  // control point (a, b) (Bernstein form).
  std::vector<Eigen::Vector4d> coeffs_;
  Kernel kernels_[kMaxOrder + 1] = {nullptr, nullptr, nullptr};
};

/// The same scheme for a curve with `Dim + 1` homogeneous components.
template <int Dim>
class SpanFormCurve {
 public:
  using HPoint = Eigen::Matrix<double, Dim + 1, 1>;
  SpanFormCurve() = default;
  /// `nets` holds, span after span, the Bezier nets of A, A' and A'' (p+1, p and p−1 points;
  /// empty when the order exceeds p). For degree ≤ 3 only the net of A is read.
  SpanFormCurve(int p, std::vector<double> breaks, const std::vector<HPoint>& nets);
  static int NetPointsPerSpan(int p) { return (p + 1) + p + std::max(p - 1, 0); }

  /// Homogeneous derivatives up to `order` at t (clamped to the domain); `hint` is a span index.
  void Evaluate(double t, int order, int* hint, HomogeneousCurveDerivs<Dim>* out) const;

 private:
  int p_ = 0;
  std::vector<double> breaks_, inv_h_;
  bool power_ = false;          // power basis (degree ≤ 3) or Bernstein form
  std::vector<HPoint> coeffs_;  // per span: p+1 power coefficients or Bezier points
};

}  // namespace tangent::nurbs
