#pragma once

// Exact ground truth for evaluation tests where long double is not enough (spans 1e-9 of their
// neighbours: the blossom identities for A'' divide second differences by h², which costs 2 log10
// (1/h) digits in any floating format). Here the knots, the parameters, the weights and the
// control points are taken as the exact rationals their doubles are, the polynomial piece is
// evaluated through its blossom in GMP rational arithmetic (exact), and only the final S and its
// partials are rounded to double. Slow (rationals grow with the degree): for tests.

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <vector>

#include "nurbs/curve.h"
#include "nurbs/surface.h"
#include "tests/nurbs/high_precision.h"

namespace tangent::nurbs::testing {

using Q = mpq_class;

/// S and its partials up to order 2 at (u, v) (clamped to the domain), exact until the final
/// rounding to double.
inline SurfacePoint EvaluateExact(const NurbsSurface& s, double u_in, double v_in) {
  const KnotVector& ku = s.knots_u();
  const KnotVector& kv = s.knots_v();
  const double ud = std::clamp(u_in, ku.domain_begin(), ku.domain_end());
  const double vd = std::clamp(v_in, kv.domain_begin(), kv.domain_end());
  const Q u(ud), v(vd);
  const int p = ku.degree(), q = kv.degree();
  const int mu = ku.FindSpan(ud), nu = kv.FindSpan(vd);
  // Derivatives from the blossom with the farther span end e: A^(a) = p!/(p−a)! Δ^a / (e − t)^a.
  const Q eu = (ku[mu + 1] - ud) >= (ud - ku[mu]) ? Q(ku[mu + 1]) : Q(ku[mu]);
  const Q ev = (kv[nu + 1] - vd) >= (vd - kv[nu]) ? Q(kv[nu + 1]) : Q(kv[nu]);
  std::array<std::array<Q, kMaxDegree + 1>, 3> ru, rv;
  std::array<Q, kMaxDegree> x;
  for (int a = 0; a <= std::min(2, p); ++a) {
    for (int r = 0; r < p; ++r) x[static_cast<size_t>(r)] = r < p - a ? u : eu;
    BlossomRow<Q>(ku, mu, x.data(), ru[static_cast<size_t>(a)].data());
  }
  for (int b = 0; b <= std::min(2, q); ++b) {
    for (int r = 0; r < q; ++r) x[static_cast<size_t>(r)] = r < q - b ? v : ev;
    BlossomRow<Q>(kv, nu, x.data(), rv[static_cast<size_t>(b)].data());
  }
  using HQ = std::array<Q, 4>;
  // t[a][b] = Σ_ij ru[a][i] rv[b][j] P_ij, accumulated over integers: each row of blossom values
  // on its common denominator, the control points (dyadic doubles) on a common power of two, so
  // the 4 (p+1)(q+1) products need no gcd and each sum is reduced to lowest terms once. (The
  // canonicalising rational += spent ~60 % of this test in gcd.) Only the partials of order ≤ 2
  // (a + b ≤ 2) are needed.
  auto common = [](const Q* r, int n, std::array<mpz_class, kMaxDegree + 1>& num, mpz_class& den) {
    den = 1;
    for (int i = 0; i < n; ++i) mpz_lcm(den.get_mpz_t(), den.get_mpz_t(), r[i].get_den_mpz_t());
    for (int i = 0; i < n; ++i) {
      num[static_cast<size_t>(i)] = r[i].get_num() * (den / r[i].get_den());
    }
  };
  std::array<std::array<mpz_class, kMaxDegree + 1>, 3> nru, nrv;
  std::array<mpz_class, 3> dru, drv;
  for (int a = 0; a <= std::min(2, p); ++a) {
    common(ru[static_cast<size_t>(a)].data(), p + 1, nru[static_cast<size_t>(a)],
           dru[static_cast<size_t>(a)]);
  }
  for (int b = 0; b <= std::min(2, q); ++b) {
    common(rv[static_cast<size_t>(b)].data(), q + 1, nrv[static_cast<size_t>(b)],
           drv[static_cast<size_t>(b)]);
  }
  std::vector<std::array<mpz_class, 4>> np(static_cast<size_t>((p + 1) * (q + 1)));
  mpz_class dp = 1;
  for (int i = 0; i <= p; ++i) {
    for (int j = 0; j <= q; ++j) {
      const Eigen::Vector4d P = s.weighted_point(mu - p + i, nu - q + j);
      for (int c = 0; c < 4; ++c) {
        if (Q(P[c]).get_den() > dp) dp = Q(P[c]).get_den();  // powers of two: the largest
      }
    }
  }
  for (int i = 0; i <= p; ++i) {
    for (int j = 0; j <= q; ++j) {
      const Eigen::Vector4d P = s.weighted_point(mu - p + i, nu - q + j);
      for (int c = 0; c < 4; ++c) {
        const Q pc(P[c]);
        np[static_cast<size_t>(i * (q + 1) + j)][static_cast<size_t>(c)] =
            pc.get_num() * (dp / pc.get_den());
      }
    }
  }
  HQ t[3][3];
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      for (Q& c : t[a][b]) c = 0;
      if (a > p || b > q || a + b > 2) continue;
      std::array<mpz_class, 4> sum;
      for (int i = 0; i <= p; ++i) {
        std::array<mpz_class, 4> row;  // Σ_j rv[b][j] P_ij
        for (int j = 0; j <= q; ++j) {
          const mpz_class& w = nrv[static_cast<size_t>(b)][static_cast<size_t>(j)];
          for (size_t c = 0; c < 4; ++c) row[c] += w * np[static_cast<size_t>(i * (q + 1) + j)][c];
        }
        const mpz_class& w = nru[static_cast<size_t>(a)][static_cast<size_t>(i)];
        for (size_t c = 0; c < 4; ++c) sum[c] += w * row[c];
      }
      const mpz_class den = dru[static_cast<size_t>(a)] * drv[static_cast<size_t>(b)] * dp;
      for (size_t c = 0; c < 4; ++c) {
        t[a][b][c] = Q(sum[c], den);
        t[a][b][c].canonicalize();
      }
    }
  }
  const Q hu = eu - u, hv = ev - v;
  auto combine = [](std::initializer_list<std::pair<Q, const HQ*>> terms) {
    HQ out;
    for (Q& c : out) c = 0;
    for (const auto& [f, h] : terms) {
      for (int c = 0; c < 4; ++c) out[static_cast<size_t>(c)] += f * (*h)[static_cast<size_t>(c)];
    }
    return out;
  };
  const HQ& A = t[0][0];
  const Q cu = Q(p) / hu, cv = Q(q) / hv;
  const HQ Au = combine({{cu, &t[1][0]}, {-cu, &t[0][0]}});
  const HQ Av = combine({{cv, &t[0][1]}, {-cv, &t[0][0]}});
  const Q cuu = p >= 2 ? Q(p * (p - 1)) / (hu * hu) : Q(0);
  const Q cvv = q >= 2 ? Q(q * (q - 1)) / (hv * hv) : Q(0);
  const HQ Auu = combine({{cuu, &t[2][0]}, {-2 * cuu, &t[1][0]}, {cuu, &t[0][0]}});
  const HQ Avv = combine({{cvv, &t[0][2]}, {-2 * cvv, &t[0][1]}, {cvv, &t[0][0]}});
  const Q cuv = Q(p * q) / (hu * hv);
  const HQ Auv = combine({{cuv, &t[1][1]}, {-cuv, &t[1][0]}, {-cuv, &t[0][1]}, {cuv, &t[0][0]}});
  // Quotient rule for S = A.xyz / A.w and its partials, exactly.
  const Q w = A[3];
  std::array<Q, 3> S, Su, Sv, Suu, Suv, Svv;
  for (size_t c = 0; c < 3; ++c) {
    S[c] = A[c] / w;
    Su[c] = (Au[c] - Au[3] * S[c]) / w;
    Sv[c] = (Av[c] - Av[3] * S[c]) / w;
    Suu[c] = (Auu[c] - 2 * Au[3] * Su[c] - Auu[3] * S[c]) / w;
    Suv[c] = (Auv[c] - Au[3] * Sv[c] - Av[3] * Su[c] - Auv[3] * S[c]) / w;
    Svv[c] = (Avv[c] - 2 * Av[3] * Sv[c] - Avv[3] * S[c]) / w;
  }
  auto round = [](const std::array<Q, 3>& a) {
    return Eigen::Vector3d(a[0].get_d(), a[1].get_d(), a[2].get_d());
  };
  return SurfacePoint{round(S), round(Su), round(Sv), round(Suu), round(Suv), round(Svv)};
}

/// C, C' and C'' at t (clamped to the domain), exact until the final rounding to double.
template <int Dim>
CurvePoint<Dim> EvaluateExact(const NurbsCurve<Dim>& c, double t_in) {
  const KnotVector& k = c.knots();
  const double td = std::clamp(t_in, k.domain_begin(), k.domain_end());
  const Q t(td);
  const int p = k.degree();
  const int mu = k.FindSpan(td);
  const Q e = (k[mu + 1] - td) >= (td - k[mu]) ? Q(k[mu + 1]) : Q(k[mu]);
  std::array<std::array<Q, kMaxDegree + 1>, 3> r;
  std::array<Q, kMaxDegree> x;
  std::array<std::array<Q, Dim + 1>, 3> b;
  for (int a = 0; a <= 2; ++a) {
    for (Q& v : b[static_cast<size_t>(a)]) v = 0;
    if (a > p) continue;
    for (int i = 0; i < p; ++i) x[static_cast<size_t>(i)] = i < p - a ? t : e;
    BlossomRow<Q>(k, mu, x.data(), r[static_cast<size_t>(a)].data());
    for (int i = 0; i <= p; ++i) {
      const auto& P = c.weighted_points()[static_cast<size_t>(mu - p + i)];
      for (int d = 0; d <= Dim; ++d) {
        b[static_cast<size_t>(a)][static_cast<size_t>(d)] +=
            r[static_cast<size_t>(a)][static_cast<size_t>(i)] * Q(P[d]);
      }
    }
  }
  const Q h = e - t;
  std::array<Q, Dim + 1> A, A1, A2;
  for (size_t d = 0; d <= Dim; ++d) {
    A[d] = b[0][d];
    A1[d] = Q(p) / h * (b[1][d] - b[0][d]);
    A2[d] = p >= 2 ? Q(p * (p - 1)) / (h * h) * (b[2][d] - 2 * b[1][d] + b[0][d]) : Q(0);
  }
  CurvePoint<Dim> out;
  for (size_t d = 0; d < Dim; ++d) {
    const Q C = A[d] / A[Dim];
    const Q C1 = (A1[d] - A1[Dim] * C) / A[Dim];
    const Q C2 = (A2[d] - 2 * A1[Dim] * C1 - A2[Dim] * C) / A[Dim];
    out.C[static_cast<Eigen::Index>(d)] = C.get_d();
    out.C1[static_cast<Eigen::Index>(d)] = C1.get_d();
    out.C2[static_cast<Eigen::Index>(d)] = C2.get_d();
  }
  return out;
}

}  // namespace tangent::nurbs::testing
