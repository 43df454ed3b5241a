#pragma once

// Power-basis span kernels of SpanFormSurface, in a header so the bicubic one inlines into
// NurbsSurface::Evaluate (no indirect call on the servo path). Internal: not part of the API.

#include <Eigen/Core>

#include "nurbs/point_types.h"

namespace tangent::nurbs::internal {

/// A span kernel: homogeneous derivatives up to its order from one span's coefficients at the
/// normalized local parameters (s, t); inv_hu, inv_hv scale derivatives to (u, v).
using SpanKernel = void (*)(const Eigen::Vector4d* coeffs, int p, int q, double s, double t,
                            double inv_hu, double inv_hv, HomogeneousSurfaceDerivs* out);

/// The bicubic power-basis kernel built with AVX2 + FMA (span_kernels_avx2.cc).
/// @pre the CPU supports AVX2 and FMA (HasAvx2Fma()).
SpanKernel BicubicKernelAvx2(int order);

/// Whether this CPU runs AVX2 and FMA instructions (CPUID, checked once).
bool HasAvx2Fma();

// Horner scheme for a polynomial of degree N with vector coefficients c[0..N] (c[k] multiplies
// x^k) and its first two derivatives; N is fixed at compile time so the loop unrolls.
template <int N, int Order>
inline void Horner(const Eigen::Vector4d* c, double x, Eigen::Vector4d* d0, Eigen::Vector4d* d1,
                   Eigen::Vector4d* d2) {
  static_assert(N >= 1 && N <= 3, "power-basis kernels cover degrees 1..3");
  constexpr int n = N;
  Eigen::Vector4d p0 = c[n];
  Eigen::Vector4d p1 = Eigen::Vector4d::Zero();
  Eigen::Vector4d p2 = Eigen::Vector4d::Zero();
  for (int k = n - 1; k >= 0; --k) {
    if constexpr (Order >= 2) p2 = p2 * x + p1;
    if constexpr (Order >= 1) p1 = p1 * x + p0;
    p0 = p0 * x + c[k];
  }
  *d0 = p0;
  if constexpr (Order >= 1) *d1 = p1;
  if constexpr (Order >= 2) *d2 = 2.0 * p2;
}

// Evaluates A and its partials on one span of degrees (P, Q) ≤ 3 in the power basis.
// Coefficient layout: C[a][b] at a*(Q+1)+b. (The runtime degrees in the SpanKernel signature
// serve the Bernstein kernel of higher degrees.)
template <int P, int Q, int Order>
void SurfaceKernel(const Eigen::Vector4d* c, int, int, double s, double t, double inv_hu,
                   double inv_hv, HomogeneousSurfaceDerivs* out) {
  constexpr int p = P;
  constexpr int q = Q;
  // Rows r0[a] = Σ_b C[a][b] t^b and their t-derivatives r1, r2.
  Eigen::Vector4d r0[kMaxDegree + 1], r1[kMaxDegree + 1], r2[kMaxDegree + 1];
  for (int a = 0; a <= p; ++a) {
    Horner<Q, Order>(c + a * (q + 1), t, &r0[a], &r1[a], &r2[a]);
  }
  Eigen::Vector4d unused1, unused2;
  // In s: A, A_s, A_ss from r0; A_t, A_st from r1; A_tt from r2.
  Horner<P, Order>(r0, s, &out->A[0], &out->A[1], &out->A[3]);
  if constexpr (Order >= 1) {
    Horner<P, Order - 1>(r1, s, &out->A[2], &out->A[4], &unused2);
    out->A[1] *= inv_hu;
    out->A[2] *= inv_hv;
  }
  if constexpr (Order >= 2) {
    Horner<P, 0>(r2, s, &out->A[5], &unused1, &unused2);
    out->A[3] *= inv_hu * inv_hu;
    out->A[4] *= inv_hu * inv_hv;
    out->A[5] *= inv_hv * inv_hv;
  }
}

}  // namespace tangent::nurbs::internal
