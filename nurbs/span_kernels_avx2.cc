// Bicubic power-basis span kernel with AVX2 + FMA, compiled on its own with -mavx2 -mfma and
// selected at run time only on CPUs that have both (see SpanFormSurface). Raw intrinsics on
// plain doubles, no Eigen: Eigen's inline functions compiled here with AVX would otherwise be
// free to replace the SSE2 copies used elsewhere (an ODR hazard on CPUs without AVX).

#include <immintrin.h>

#include "nurbs/span_kernels.h"

namespace tangent::nurbs::internal {

namespace {

// Horner in x over four homogeneous coefficients c[0..3] (c[k] multiplies x^k), with the first
// and second derivatives when Order asks: each 4-vector (w·S, w) is one __m256d.
template <int Order>
inline void Horner3(const double* c, __m256d x, __m256d* d0, __m256d* d1, __m256d* d2) {
  __m256d p0 = _mm256_loadu_pd(c + 12);
  __m256d p1 = _mm256_setzero_pd();
  __m256d p2 = _mm256_setzero_pd();
  for (int k = 2; k >= 0; --k) {
    if constexpr (Order >= 2) p2 = _mm256_fmadd_pd(p2, x, p1);
    if constexpr (Order >= 1) p1 = _mm256_fmadd_pd(p1, x, p0);
    p0 = _mm256_fmadd_pd(p0, x, _mm256_loadu_pd(c + 4 * k));
  }
  *d0 = p0;
  if constexpr (Order >= 1) *d1 = p1;
  if constexpr (Order >= 2) *d2 = _mm256_add_pd(p2, p2);
}

// Same, over coefficients already in registers.
template <int Order>
inline void Horner3(const __m256d* c, __m256d x, __m256d* d0, __m256d* d1, __m256d* d2) {
  __m256d p0 = c[3];
  __m256d p1 = _mm256_setzero_pd();
  __m256d p2 = _mm256_setzero_pd();
  for (int k = 2; k >= 0; --k) {
    if constexpr (Order >= 2) p2 = _mm256_fmadd_pd(p2, x, p1);
    if constexpr (Order >= 1) p1 = _mm256_fmadd_pd(p1, x, p0);
    p0 = _mm256_fmadd_pd(p0, x, c[k]);
  }
  *d0 = p0;
  if constexpr (Order >= 1) *d1 = p1;
  if constexpr (Order >= 2) *d2 = _mm256_add_pd(p2, p2);
}

template <int Order>
void Bicubic(const Eigen::Vector4d* coeffs, int, int, double s, double t, double inv_hu,
             double inv_hv, HomogeneousSurfaceDerivs* out) {
  const double* c = coeffs[0].data();  // 16 contiguous 4-vectors, C[a][b] at (4a + b)·4.
  const __m256d vt = _mm256_set1_pd(t);
  const __m256d vs = _mm256_set1_pd(s);
  __m256d r0[4], r1[4], r2[4];
  for (int a = 0; a < 4; ++a) Horner3<Order>(c + 16 * a, vt, &r0[a], &r1[a], &r2[a]);
  __m256d a0, a_u, a_uu, a_v, a_uv, a_vv, unused1, unused2;
  Horner3<Order>(r0, vs, &a0, &a_u, &a_uu);
  _mm256_storeu_pd(out->A[0].data(), a0);
  if constexpr (Order >= 1) {
    Horner3<Order - 1>(r1, vs, &a_v, &a_uv, &unused2);
    _mm256_storeu_pd(out->A[1].data(), _mm256_mul_pd(a_u, _mm256_set1_pd(inv_hu)));
    _mm256_storeu_pd(out->A[2].data(), _mm256_mul_pd(a_v, _mm256_set1_pd(inv_hv)));
  }
  if constexpr (Order >= 2) {
    Horner3<0>(r2, vs, &a_vv, &unused1, &unused2);
    _mm256_storeu_pd(out->A[3].data(), _mm256_mul_pd(a_uu, _mm256_set1_pd(inv_hu * inv_hu)));
    _mm256_storeu_pd(out->A[4].data(), _mm256_mul_pd(a_uv, _mm256_set1_pd(inv_hu * inv_hv)));
    _mm256_storeu_pd(out->A[5].data(), _mm256_mul_pd(a_vv, _mm256_set1_pd(inv_hv * inv_hv)));
  }
}

}  // namespace

SpanKernel BicubicKernelAvx2(int order) {
  switch (order) {
    case 0:
      return &Bicubic<0>;
    case 1:
      return &Bicubic<1>;
    default:
      return &Bicubic<2>;
  }
}

}  // namespace tangent::nurbs::internal
