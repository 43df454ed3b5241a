#pragma once

#include <algorithm>
#include <cstdint>
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

/// x clamped to [0, 1], NaN to 0.
inline double ClampUnit(double x) { return x >= 0.0 ? (x <= 1.0 ? x : 1.0) : 0.0; }

/// Index i with `breaks[i] <= x < breaks[i+1]`, clamped to [0, breaks.size() - 2] (NaN: 0);
/// tries `hint` first, then a branchless binary search.
int FindInterval(const std::vector<double>& breaks, double x, int hint);

/// Bernstein polynomials at s ∈ [0, 1] of degrees p, p−1, p−2: b[d][i] = B_{i,p−d}(s) (rows of
/// negative degree are left untouched), from the de Casteljau triangle.
void BernsteinValues(int p, double s, double b[kMaxOrder + 1][kMaxDegree + 1]);

/// M with power coefficient k = Σ_i M(k, i) b_i for a degree-p Bezier polynomial in s ∈ [0, 1]:
/// M(k, i) = C(p, k) C(k, i) (−1)^(k−i) for i ≤ k, 0 otherwise.
Eigen::MatrixXd BezierToPowerMatrix(int p);

/// The Bernstein-form kernel: `c` holds the span's Bezier nets of A and its partials.
template <int Order>
void BernsteinKernel(const Eigen::Vector4d* c, int p, int q, double s, double t, double inv_hu,
                     double inv_hv, HomogeneousSurfaceDerivs* out);

/// Relative error a span's power form may have in any derivative family against its Bernstein
/// form (which builds derivatives from hodograph nets and is well conditioned). Converting to
/// monomials differences nearly equal Bezier points: the k-th derivative loses about
/// k log10(H/h) digits on a span h much shorter than the part's size H (measured: S_uu off by
/// 1.3e-8 at h/H = 1e-3 and by order one at 1e-7). Measured on the Cartesian derivatives, so
/// the quotient rule's amplification is included. Each family is judged at each point against
/// its size there (kPointScaleFloor below), as docs/nurbs.md measures: against its largest value
/// on the span, the power basis's own conditioning let 1.6e-12 through where a second
/// derivative is small at a point (issue 38). 2e-13 leaves a margin of 5 for points between
/// the ones checked against the 1e-12 of docs/nurbs.md.
inline constexpr double kPowerFormTolerance = 2e-13;
/// The smallest size of a derivative family at a point, as a fraction of its largest on the
/// span, that the certification measures its error against (where a second derivative passes
/// through zero no basis resolves it relative to itself).
inline constexpr double kPointScaleFloor = 1e-2;

/// Whether a span's power coefficients reproduce its Bernstein nets to kPowerFormTolerance
/// (Cartesian derivatives, each order relative to its size at the point, floored at
/// kPointScaleFloor of its largest on the span), checked on a 5 x 5 grid of the span.
bool PowerFormIsExact(const Eigen::Vector4d* power, const Eigen::Vector4d* nets, int p, int q,
                      double inv_hu, double inv_hv, SpanKernel power_kernel);

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
    // Clamp to the span so a parameter outside the domain evaluates the domain edge (a NaN one
    // the domain's start: FindInterval gives span 0 and ClampUnit 0).
    const double s = internal::ClampUnit((u - u0) * inv_hu);
    const double t = internal::ClampUnit((v - v0) * inv_hv);
    const size_t span = static_cast<size_t>(i * num_spans_v() + j);
    const Eigen::Vector4d* c = coeffs_.data() + offsets_[span];
    if (net_form_[span]) {
      net_kernels_[Order](c, p_, q_, s, t, inv_hu, inv_hv, out);
    } else if (bicubic_ && !avx2_) {
      internal::SurfaceKernel<3, 3, Order>(c, 3, 3, s, t, inv_hu, inv_hv, out);
    } else {
      kernels_[Order](c, p_, q_, s, t, inv_hu, inv_hv, out);
    }
  }

  /// True when the pieces are held in the power basis (both degrees ≤ 3), except on the spans
  /// where that form is not exact (net_form_spans()).
  bool uses_power_basis() const { return power_; }
  /// Spans kept in the Bernstein form although the degrees allow the power form: too short for
  /// it (kPowerFormTolerance).
  int net_form_spans() const {
    return power_ ? static_cast<int>(std::count(net_form_.begin(), net_form_.end(), 1)) : 0;
  }
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
  // Per span from offsets_[span]: C[a][b] at a*(q+1)+b, the coefficient of s^a t^b (power
  // basis), or (net_form_[span]) the Bezier nets of A and its partials (Bernstein form).
  std::vector<Eigen::Vector4d> coeffs_;
  std::vector<size_t> offsets_;
  std::vector<uint8_t> net_form_;
  Kernel kernels_[kMaxOrder + 1] = {nullptr, nullptr, nullptr};
  Kernel net_kernels_[kMaxOrder + 1] = {nullptr, nullptr, nullptr};
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
  /// Spans kept in the Bernstein form although the degree allows the power form (too short).
  int net_form_spans() const {
    return power_ ? static_cast<int>(std::count(net_form_.begin(), net_form_.end(), 1)) : 0;
  }

 private:
  void PowerPiece(const HPoint* c, double s, double inv_h, int order,
                  HomogeneousCurveDerivs<Dim>* out) const;
  void NetPiece(const HPoint* c, double s, double inv_h, int order,
                HomogeneousCurveDerivs<Dim>* out) const;

  int p_ = 0;
  std::vector<double> breaks_, inv_h_;
  bool power_ = false;  // power basis allowed (degree ≤ 3)
  // Per span from offsets_[span]: p+1 power coefficients, or (net_form_[span]) the Bezier nets
  // of A, A' and A''.
  std::vector<HPoint> coeffs_;
  std::vector<size_t> offsets_;
  std::vector<uint8_t> net_form_;
};

}  // namespace tangent::nurbs
