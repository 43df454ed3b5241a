#include "contact/pole_chart.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "contact/poles.h"

namespace tangent::contact {

namespace {

// Below this distance from the row (a fraction of the across domain) U = S_a/ρ is taken as its
// limit ∂S_a/∂ρ: S_a carries an absolute rounding error of ~eps |S|, which S_a/ρ would amplify
// by 1/ρ, while the limit is off by O(ρ) only.
constexpr double kLimitRho = 1e-8;
// Below this distance the second partials are those at this distance along the same angle:
// Q_ij divides S_aa's rounding by ρ², so nearer the row it would be noise. They only shape
// Newton's matrix and the Hessian's u-terms, where an O(ρ) error keeps Newton contracting by
// that factor per step.
constexpr double kSecondOrderRho = 1e-4;
// Chart coordinates this near the pole (in units of eps (|P| + PoleChart::length)) are the pole
// itself.
constexpr double kPoleSnap = 1024.0;
// Samples of the row's departure directions, for the inverse's starting angle.
constexpr int kStartAngles = 32;

Eigen::Matrix<double, 2, 3> Tangent(const PoleChart& c) {
  Eigen::Matrix<double, 2, 3> t;
  t.row(0) = c.e1.transpose();
  t.row(1) = c.e2.transpose();
  return t;
}

// (u, v) from the angle parameter a and the distance ρ from the row.
Eigen::Vector2d Params(const PoleChart& c, double a, double rho) {
  Eigen::Vector2d uv;
  uv[1 - c.across] = a;
  uv[c.across] = c.bound + c.inward * rho;
  return uv;
}

// The partials along the angle parameter and along ρ (toward the inside), to second order.
struct PolarPartials {
  Eigen::Vector3d S, S_a, S_r, S_aa, S_ar, S_rr;
};
PolarPartials Polar(const PoleChart& c, const nurbs::SurfacePoint& p) {
  PolarPartials q;
  q.S = p.S;
  const bool across_v = c.across == 1;
  q.S_a = across_v ? p.S_u : p.S_v;
  q.S_r = c.inward * (across_v ? p.S_v : p.S_u);
  q.S_aa = across_v ? p.S_uu : p.S_vv;
  q.S_ar = c.inward * p.S_uv;
  q.S_rr = across_v ? p.S_vv : p.S_uu;
  return q;
}

// U = S_a/ρ, or its limit at the row.
Eigen::Vector3d Divided(const PoleChart& c, const PolarPartials& q, double rho) {
  return rho > kLimitRho * c.width ? Eigen::Vector3d(q.S_a / rho) : q.S_ar;
}

// The chart's second partials (x x, x y, y y) from polar partials at distance rho ≥
// kSecondOrderRho.
void SecondPartials(const PoleChart& c, const PolarPartials& q, double rho,
                    const Eigen::Matrix2d& M, const Eigen::Matrix<double, 3, 2>& J,
                    nurbs::SurfacePoint* out) {
  const Eigen::Matrix<double, 2, 3> T = Tangent(c);
  const Eigen::Vector3d aa = q.S_aa / (rho * rho), ar = q.S_ar / rho;
  auto second = [&](int i, int j) {
    const Eigen::Vector3d Q = aa * (M(0, i) * M(0, j)) +
                              ar * (M(0, i) * M(1, j) + M(0, j) * M(1, i)) +
                              q.S_rr * (M(1, i) * M(1, j));
    return Eigen::Vector3d(Q - J * (T * Q));
  };
  out->S_uu = second(0, 0);
  out->S_uv = second(0, 1);
  out->S_vv = second(1, 1);
}

// The divided Jacobian A = [T U, T S_ρ]: ∂(x, y)/∂(ρ Δa, Δρ).
Eigen::Matrix2d DividedJacobian(const PoleChart& c, const Eigen::Vector3d& U,
                                const Eigen::Vector3d& S_r) {
  const Eigen::Matrix<double, 2, 3> T = Tangent(c);
  Eigen::Matrix2d A;
  A.col(0) = T * U;
  A.col(1) = T * S_r;
  return A;
}

// S, S_x, S_y in the body frame at uv into *out, with the polar partials there, M = A⁻¹ and the
// chart's first partials Jc = [S_x S_y] (what the second partials need).
void FirstPartials(const nurbs::NurbsSurface& s, const PoleChart& c, const Eigen::Vector2d& uv,
                   nurbs::SpanHint* hint, PolarPartials* q, Eigen::Matrix2d* M,
                   Eigen::Matrix<double, 3, 2>* Jc, nurbs::SurfacePoint* out) {
  nurbs::SurfacePoint p;
  s.Evaluate<2>(uv[0], uv[1], hint, &p);
  *q = Polar(c, p);
  const Eigen::Vector3d U = Divided(c, *q, std::max(c.Rho(uv), 0.0));
  *M = DividedJacobian(c, U, q->S_r).inverse();
  Eigen::Matrix<double, 3, 2> J;
  J << U, q->S_r;
  *Jc = J * *M;
  out->S = p.S;
  out->S_u = Jc->col(0);
  out->S_v = Jc->col(1);
}

// The chart of a pole row, false at a vertex.
bool MakeChart(const nurbs::NurbsSurface& s, const internal::PoleRow& row, PoleChart* chart) {
  if (internal::IsVertex(s, row)) return false;
  const nurbs::KnotVector& ka = row.across == 1 ? s.knots_u() : s.knots_v();
  const nurbs::KnotVector& kx = row.across == 1 ? s.knots_v() : s.knots_u();
  PoleChart c;
  c.across = row.across;
  c.bound = row.bound;
  c.inward = row.inward;
  c.width = kx.domain_end() - kx.domain_begin();
  const Eigen::Vector2d at = Params(c, ka.domain_begin(), 0.0);
  const nurbs::SurfacePoint p = s.Evaluate(at[0], at[1], 2);
  c.P = p.S;
  c.n = nurbs::UnitNormal(s, at[0], at[1], p);
  const Eigen::Vector3d leave = Polar(c, p).S_r;
  const Eigen::Vector3d t = leave - leave.dot(c.n) * c.n;
  if (!(t.norm() > 0.0) || !c.n.allFinite()) return false;
  c.e1 = t.normalized();
  c.length = leave.norm() * c.width;
  c.e2 = c.n.cross(c.e1);
  *chart = c;
  return true;
}

}  // namespace

bool FindPoleChart(const nurbs::NurbsSurface& s, const Eigen::Vector2d& uv, double fraction,
                   PoleChart* chart) {
  const internal::PoleRow row = internal::FindPoleRow(s, uv, fraction);
  return row.found && MakeChart(s, row, chart);
}

void SurfacePoles::Find(const nurbs::NurbsSurface& s) {
  any = false;
  for (int across = 0; across < 2; ++across) {
    const bool periodic = across == 1 ? s.periodic_v() : s.periodic_u();
    const nurbs::KnotVector& kx = across == 1 ? s.knots_v() : s.knots_u();
    const nurbs::KnotVector& ka = across == 1 ? s.knots_u() : s.knots_v();
    for (int upper = 0; upper < 2; ++upper) {
      PoleChart& c = edge[2 * across + upper];
      c = PoleChart{};
      if (periodic) continue;
      internal::PoleRow row;
      row.found = true;
      row.across = across;
      row.bound = upper ? kx.domain_end() : kx.domain_begin();
      row.inward = upper ? -1.0 : 1.0;
      Eigen::Vector2d mid;
      mid[1 - across] = 0.5 * (ka.domain_begin() + ka.domain_end());
      mid[across] = row.bound;
      if (internal::IsPoleRowAt(s, across, row.bound, mid) && MakeChart(s, row, &c)) any = true;
    }
  }
}

const PoleChart* SurfacePoles::Near(const Eigen::Vector2d& uv, double fraction) const {
  if (!any) return nullptr;
  for (const PoleChart& c : edge) {
    if (c.valid() && c.Rho(uv) <= fraction * c.width) return &c;
  }
  return nullptr;
}

bool ChartHolds(const nurbs::NurbsSurface& s, const PoleChart& chart, const Eigen::Vector2d& uv,
                nurbs::SpanHint* hint) {
  const double rho = chart.Rho(uv);
  if (!(rho <= kChartReach * chart.width)) return false;
  if (rho <= kLimitRho * chart.width) return true;  // the pole's own normal
  nurbs::SurfacePoint p;
  s.Evaluate<1>(uv[0], uv[1], hint, &p);
  const Eigen::Vector3d N = p.S_u.cross(p.S_v);
  return std::abs(N.dot(chart.n)) >= kChartNormalCosine * N.norm();
}

double ChartPrecision(const PoleChart& chart, const Eigen::Vector2d& uv) {
  const double rho = std::max(chart.Rho(uv), 1e-300) / chart.width;  // a fraction of the domain
  const double eps = std::numeric_limits<double>::epsilon();
  const double rounding = 8.0 * eps * (1.0 + chart.P.norm() / chart.length) / rho;
  return rho > kLimitRho ? rounding : std::min(rounding, rho);
}

Eigen::Vector2d ChartCoordinates(const nurbs::NurbsSurface& s, const PoleChart& chart,
                                 const Eigen::Vector2d& uv, nurbs::SpanHint* hint) {
  nurbs::SurfacePoint p;
  s.Evaluate<0>(uv[0], uv[1], hint, &p);
  return Tangent(chart) * (p.S - chart.P);
}

Eigen::Matrix2d ChartFromParameters(const nurbs::NurbsSurface& s, const PoleChart& chart,
                                    const Eigen::Vector2d& uv, nurbs::SpanHint* hint) {
  nurbs::SurfacePoint p;
  s.Evaluate<1>(uv[0], uv[1], hint, &p);
  const Eigen::Matrix<double, 2, 3> T = Tangent(chart);
  Eigen::Matrix2d d;
  d.col(0) = T * p.S_u;
  d.col(1) = T * p.S_v;
  return d;
}

bool ChartParameters(const nurbs::NurbsSurface& s, const PoleChart& c, const Eigen::Vector2d& xy,
                     const Eigen::Vector2d& guess, nurbs::SpanHint* hint, Eigen::Vector2d* uv) {
  const nurbs::KnotVector& ka = c.across == 1 ? s.knots_u() : s.knots_v();
  const double a_lo = ka.domain_begin(), a_hi = ka.domain_end(), a_w = a_hi - a_lo;
  const bool periodic = c.across == 1 ? s.periodic_u() : s.periodic_v();
  const Eigen::Matrix<double, 2, 3> T = Tangent(c);
  const double r = xy.norm();
  nurbs::SurfacePoint p;
  auto departure = [&](double a) {
    const Eigen::Vector2d at = Params(c, a, 0.0);
    s.Evaluate<2>(at[0], at[1], hint, &p);
    return Eigen::Vector2d(T * Polar(c, p).S_r);
  };
  double a = guess[1 - c.across];
  Eigen::Vector2d t = departure(a);
  // So near the pole the angle is rounding noise (T(S − P) carries ~eps |P|, so the angle ~eps
  // |P| / r: 1e-3 rad at the snap radius): the guess's angle is kept, so a point resting on the
  // pole does not swing round it from one solve to the next. The point is then off by at most
  // 2 r along the plane (1e-14 m for a 5 mm sphere).
  const double snap = kPoleSnap * std::numeric_limits<double>::epsilon() * (c.P.norm() + c.length);
  if (!(r > snap)) {
    *uv = Params(c, a, r / t.norm());
    return true;
  }
  const Eigen::Vector2d dir = xy / r;
  // Starting angle: the guess's, unless another sampled departure points nearer xy's direction.
  double best = t.normalized().dot(dir);
  if (best < 0.9) {
    for (int k = 0; k < kStartAngles; ++k) {
      const double ak = a_lo + a_w * (k + 0.5) / kStartAngles;
      const Eigen::Vector2d tk = departure(ak);
      const double cosine = tk.normalized().dot(dir);
      if (cosine > best) {
        best = cosine;
        a = ak;
        t = tk;
      }
    }
  }
  double rho = r / t.norm();
  const double tol = 8.0 * std::numeric_limits<double>::epsilon() * (c.P.norm() + r);
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector2d at = Params(c, a, rho);
    s.Evaluate<2>(at[0], at[1], hint, &p);
    const PolarPartials q = Polar(c, p);
    const Eigen::Vector2d G = T * (q.S - c.P) - xy;
    if (G.norm() <= tol) {
      // Still a graph over the tangent plane here (the normal within 60° of the pole's): else
      // the chart has reached a fold of the surface, where its inverse is not this point.
      const Eigen::Vector3d N = Divided(c, q, rho).cross(q.S_r);
      *uv = at;
      return std::abs(N.dot(c.n)) >= kChartNormalCosine * N.norm();
    }
    const Eigen::Vector2d step =
        -DividedJacobian(c, Divided(c, q, rho), q.S_r).inverse() * G;  // (ρ Δa, Δρ)
    if (!step.allFinite()) return false;
    const double next_rho = rho + step[1];
    if (rho > 0.0) a += step[0] / rho;  // (at the row itself the angle is not defined yet)
    rho = next_rho > 0.0 ? next_rho : 0.5 * rho;
    if (periodic) {
      a = a_lo + std::fmod(std::fmod(a - a_lo, a_w) + a_w, a_w);
    } else if (a < a_lo || a > a_hi) {
      a = std::clamp(a, a_lo, a_hi);
    }
    if (rho > c.width) rho = c.width;
  }
  // Not to rounding: taken when the residual is within 1e-12 of the point's size (it then
  // corrects on the next call), else there is no such point.
  const Eigen::Vector2d at = Params(c, a, rho);
  s.Evaluate<0>(at[0], at[1], hint, &p);
  *uv = at;
  return (T * (p.S - c.P) - xy).norm() <= 1e-12 * (c.P.norm() + r);
}

void EvaluateCharted(const nurbs::NurbsSurface& s, const PoleChart& chart, const BodyPose& pose,
                     const Eigen::Vector2d& uv, nurbs::SpanHint* hint, PlacedSurfacePoint* out) {
  PolarPartials q;
  Eigen::Matrix2d M;
  Eigen::Matrix<double, 3, 2> J;
  nurbs::SurfacePoint& b = out->body;
  FirstPartials(s, chart, uv, hint, &q, &M, &J, &b);
  const double rho = std::max(chart.Rho(uv), 0.0);
  const double second_rho = kSecondOrderRho * chart.width;
  if (rho >= second_rho) {
    SecondPartials(chart, q, rho, M, J, &b);
  } else {
    // At the same angle, second_rho from the row.
    Eigen::Vector2d off = uv;
    off[chart.across] = chart.bound + chart.inward * second_rho;
    PolarPartials q2;
    Eigen::Matrix2d M2;
    Eigen::Matrix<double, 3, 2> J2;
    nurbs::SurfacePoint b2;
    FirstPartials(s, chart, off, hint, &q2, &M2, &J2, &b2);
    SecondPartials(chart, q2, second_rho, M2, J2, &b);
  }
  PlaceBody(pose, out);
  out->pole = false;
  out->charted = true;
}

}  // namespace tangent::contact
