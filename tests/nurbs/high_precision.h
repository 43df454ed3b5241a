#pragma once

// Ground truth for evaluation tests: the surface's polynomial piece evaluated through its blossom
// in long double (64-bit mantissa on x86-64, 2^11 times finer than double). Derivatives use the
// exact blossom identities A' = p (b(t^{p-1}, e) − b(t^p))/(e − t) and
// A'' = p(p−1) (b(t^{p-2}, e, e) − 2 b(t^{p-1}, e) + b(t^p))/(e − t)², with e the farther span end.

#include <algorithm>

#include "nurbs/surface.h"

namespace tangent::nurbs::testing {

using Real = long double;
using HP = Eigen::Matrix<Real, 4, 1>;

// Blossom row of span mu at arguments x[0..p-1], as OsloAlphaRow but in the arithmetic T (long
// double here, GMP rationals in exact_truth.h).
template <class T>
void BlossomRow(const KnotVector& k, int mu, const T* x, T* a) {
  const int p = k.degree();
  a[0] = 1;
  for (int r = 1; r <= p; ++r) {
    a[r] = 0;
    for (int b = r; b >= 0; --b) {
      T value = 0;
      if (b <= r - 1) {
        const int i = mu - r + 1 + b;
        value += a[b] * (T(k[i + r]) - x[r - 1]) / (T(k[i + r]) - T(k[i]));
      }
      if (b >= 1) {
        const int i = mu - r + b;
        value += a[b - 1] * (x[r - 1] - T(k[i])) / (T(k[i + r]) - T(k[i]));
      }
      a[b] = value;
    }
  }
}

/// S and its partials up to order 2, computed in long double and rounded to double at the end.
inline SurfacePoint EvaluateHighPrecision(const NurbsSurface& s, double u_in, double v_in) {
  const KnotVector& ku = s.knots_u();
  const KnotVector& kv = s.knots_v();
  const Real u = std::clamp(u_in, ku.domain_begin(), ku.domain_end());
  const Real v = std::clamp(v_in, kv.domain_begin(), kv.domain_end());
  const int p = ku.degree(), q = kv.degree();
  const int mu = ku.FindSpan(static_cast<double>(u)), nu = kv.FindSpan(static_cast<double>(v));
  const Real eu = (ku[mu + 1] - u) >= (u - ku[mu]) ? Real(ku[mu + 1]) : Real(ku[mu]);
  const Real ev = (kv[nu + 1] - v) >= (v - kv[nu]) ? Real(kv[nu + 1]) : Real(kv[nu]);
  Real ru[3][kMaxDegree + 1] = {}, rv[3][kMaxDegree + 1] = {};
  Real x[kMaxDegree] = {};
  for (int a = 0; a <= std::min(2, p); ++a) {
    for (int r = 0; r < p; ++r) x[r] = r < p - a ? u : eu;
    BlossomRow<Real>(ku, mu, x, ru[a]);
  }
  for (int b = 0; b <= std::min(2, q); ++b) {
    for (int r = 0; r < q; ++r) x[r] = r < q - b ? v : ev;
    BlossomRow<Real>(kv, nu, x, rv[b]);
  }
  HP t[3][3];
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      t[a][b].setZero();
      if (a > p || b > q) continue;
      for (int i = 0; i <= p; ++i)
        for (int j = 0; j <= q; ++j)
          t[a][b] += ru[a][i] * rv[b][j] * s.weighted_point(mu - p + i, nu - q + j).cast<Real>();
    }
  }
  const Real hu = eu - u, hv = ev - v;
  HP A = t[0][0];
  HP Au = Real(p) / hu * (t[1][0] - t[0][0]);
  HP Av = Real(q) / hv * (t[0][1] - t[0][0]);
  HP Auu =
      p >= 2 ? HP(Real(p * (p - 1)) / (hu * hu) * (t[2][0] - 2 * t[1][0] + t[0][0])) : HP::Zero();
  HP Auv = Real(p * q) / (hu * hv) * (t[1][1] - t[1][0] - t[0][1] + t[0][0]);
  HP Avv =
      q >= 2 ? HP(Real(q * (q - 1)) / (hv * hv) * (t[0][2] - 2 * t[0][1] + t[0][0])) : HP::Zero();
  using V = Eigen::Matrix<Real, 3, 1>;
  const Real w = A[3];
  const V S = A.head<3>() / w;
  const V Su = (Au.head<3>() - Au[3] * S) / w;
  const V Sv = (Av.head<3>() - Av[3] * S) / w;
  const V Suu = (Auu.head<3>() - 2 * Au[3] * Su - Auu[3] * S) / w;
  const V Suv = (Auv.head<3>() - Au[3] * Sv - Av[3] * Su - Auv[3] * S) / w;
  const V Svv = (Avv.head<3>() - 2 * Av[3] * Sv - Avv[3] * S) / w;
  return SurfacePoint{S.cast<double>(),   Su.cast<double>(),  Sv.cast<double>(),
                      Suu.cast<double>(), Suv.cast<double>(), Svv.cast<double>()};
}

}  // namespace tangent::nurbs::testing
