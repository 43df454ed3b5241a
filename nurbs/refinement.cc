#include "nurbs/refinement.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "nurbs/basis.h"
#include "nurbs/bezier_nets.h"

namespace tangent::nurbs {

namespace {

using internal::AlphaRow;
using internal::CurveBezierNet;
using internal::DerivativeBezierRows;
using internal::DomainSpans;

std::vector<double> ClampedBezierKnots(int p, double a, double b) {
  std::vector<double> knots(static_cast<size_t>(2 * (p + 1)), a);
  std::fill(knots.begin() + p + 1, knots.end(), b);
  return knots;
}

}  // namespace

AlphaMatrix OsloAlphaMatrix(const KnotVector& old_knots, const KnotVector& refined) {
  if (!old_knots.IsRefinedBy(refined)) {
    throw std::invalid_argument(
        "knot refinement: the new knot vector must have the same degree and domain and contain "
        "every interior knot of the old one with at least its multiplicity");
  }
  const int p = old_knots.degree();
  AlphaMatrix m;
  m.degree = p;
  const int n_new = refined.num_basis();
  m.first.resize(static_cast<size_t>(n_new));
  m.alpha.resize(static_cast<size_t>(n_new));
  double x[kMaxDegree];
  for (int j = 0; j < n_new; ++j) {
    // Old span holding t_j (clamped into the domain), then the blossom at t_{j+1..j+p}.
    const int mu = old_knots.FindSpan(refined[j]);
    for (int r = 0; r < p; ++r) x[r] = refined[j + 1 + r];
    OsloAlphaRow(old_knots, mu, x, &m.alpha[static_cast<size_t>(j)]);
    m.first[static_cast<size_t>(j)] = mu - p;
  }
  return m;
}

namespace {

template <int Dim>
NurbsCurve<Dim> ApplyAlpha(const NurbsCurve<Dim>& curve, const AlphaMatrix& m, KnotVector knots) {
  using HPoint = typename NurbsCurve<Dim>::HPoint;
  std::vector<HPoint> cpw(m.first.size(), HPoint::Zero());
  for (size_t j = 0; j < cpw.size(); ++j) {
    for (int k = 0; k <= m.degree; ++k) {
      cpw[j] += m.alpha[j][static_cast<size_t>(k)] *
                curve.weighted_points()[static_cast<size_t>(m.first[j] + k)];
    }
  }
  return NurbsCurve<Dim>::FromHomogeneous(std::move(knots), std::move(cpw));
}

NurbsSurface ApplyAlpha(const NurbsSurface& surface, Direction dir, const AlphaMatrix& m,
                        KnotVector knots) {
  const bool in_u = dir == Direction::kU;
  const int n_new = static_cast<int>(m.first.size());
  const int nu = in_u ? n_new : surface.num_u();
  const int nv = in_u ? surface.num_v() : n_new;
  std::vector<Eigen::Vector4d> cpw(static_cast<size_t>(nu * nv), Eigen::Vector4d::Zero());
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const size_t row = static_cast<size_t>(in_u ? i : j);
      Eigen::Vector4d& out = cpw[static_cast<size_t>(i * nv + j)];
      for (int k = 0; k <= m.degree; ++k) {
        const int old = m.first[row] + k;
        out += m.alpha[row][static_cast<size_t>(k)] *
               (in_u ? surface.weighted_point(old, j) : surface.weighted_point(i, old));
      }
    }
  }
  return NurbsSurface::FromHomogeneous(in_u ? std::move(knots) : surface.knots_u(),
                                       in_u ? surface.knots_v() : std::move(knots), std::move(cpw));
}

// Alpha matrix restricting a spline on `k` to [lo, hi] inside its domain, clamped at both ends:
// new knots lo^(p+1), the old interior knots in (lo, hi) with their multiplicities, hi^(p+1).
// Row j is the blossom at the new knots t_{j+1..j+p} of the old piece on the span holding t_j.
AlphaMatrix RestrictionAlpha(const KnotVector& k, double lo, double hi, KnotVector* restricted) {
  const int p = k.degree();
  std::vector<double> knots(static_cast<size_t>(p + 1), lo);
  for (int i = p + 1; i < k.num_basis(); ++i) {
    if (k[i] > lo && k[i] < hi) knots.push_back(k[i]);
  }
  for (int r = 0; r <= p; ++r) knots.push_back(hi);
  *restricted = KnotVector(p, std::move(knots));
  AlphaMatrix m;
  m.degree = p;
  double x[kMaxDegree];
  for (int j = 0; j < restricted->num_basis(); ++j) {
    const int mu = k.FindSpan((*restricted)[j]);
    for (int r = 0; r < p; ++r) x[r] = (*restricted)[j + 1 + r];
    m.alpha.emplace_back();
    OsloAlphaRow(k, mu, x, &m.alpha.back());
    m.first.push_back(mu - p);
  }
  return m;
}

void CheckSplit(const KnotVector& k, double t) {
  if (!(t > k.domain_begin() && t < k.domain_end())) {
    std::ostringstream os;
    os << "split: t = " << t << " is not strictly inside the domain (" << k.domain_begin() << ", "
       << k.domain_end() << ")";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

template <int Dim>
NurbsCurve<Dim> RefineKnots(const NurbsCurve<Dim>& curve, const KnotVector& refined) {
  return ApplyAlpha(curve, OsloAlphaMatrix(curve.knots(), refined), refined);
}

NurbsSurface RefineKnots(const NurbsSurface& surface, Direction dir, const KnotVector& refined) {
  const KnotVector& k = dir == Direction::kU ? surface.knots_u() : surface.knots_v();
  return ApplyAlpha(surface, dir, OsloAlphaMatrix(k, refined), refined);
}

template <int Dim>
std::pair<NurbsCurve<Dim>, NurbsCurve<Dim>> Split(const NurbsCurve<Dim>& curve, double t) {
  const KnotVector& k = curve.knots();
  CheckSplit(k, t);
  KnotVector left = k, right = k;
  const AlphaMatrix ml = RestrictionAlpha(k, k.domain_begin(), t, &left);
  const AlphaMatrix mr = RestrictionAlpha(k, t, k.domain_end(), &right);
  return {ApplyAlpha(curve, ml, left), ApplyAlpha(curve, mr, right)};
}

std::pair<NurbsSurface, NurbsSurface> Split(const NurbsSurface& surface, Direction dir, double t) {
  const KnotVector& k = dir == Direction::kU ? surface.knots_u() : surface.knots_v();
  CheckSplit(k, t);
  KnotVector left = k, right = k;
  const AlphaMatrix ml = RestrictionAlpha(k, k.domain_begin(), t, &left);
  const AlphaMatrix mr = RestrictionAlpha(k, t, k.domain_end(), &right);
  return {ApplyAlpha(surface, dir, ml, left), ApplyAlpha(surface, dir, mr, right)};
}

namespace {

// Boehm insertion on a sequence of homogeneous points (Piegl & Tiller A5.1).
template <class HPoint>
std::vector<HPoint> BoehmInsert(const KnotVector& k, const std::vector<HPoint>& pw, double t,
                                int times, std::vector<double>* new_knots) {
  const int p = k.degree();
  const int span = k.FindSpan(t);
  const int s = k.Multiplicity(t);
  const int np = k.num_basis() - 1;
  std::vector<HPoint> q(pw.size() + static_cast<size_t>(times));
  for (int i = 0; i <= span - p; ++i) q[static_cast<size_t>(i)] = pw[static_cast<size_t>(i)];
  for (int i = span - s; i <= np; ++i) {
    q[static_cast<size_t>(i + times)] = pw[static_cast<size_t>(i)];
  }
  std::vector<HPoint> r(static_cast<size_t>(p + 1));
  for (int i = 0; i <= p - s; ++i)
    r[static_cast<size_t>(i)] = pw[static_cast<size_t>(span - p + i)];
  int l = 0;
  for (int j = 1; j <= times; ++j) {
    l = span - p + j;
    for (int i = 0; i <= p - j - s; ++i) {
      const double alpha = (t - k[l + i]) / (k[i + span + 1] - k[l + i]);
      r[static_cast<size_t>(i)] =
          alpha * r[static_cast<size_t>(i + 1)] + (1.0 - alpha) * r[static_cast<size_t>(i)];
    }
    q[static_cast<size_t>(l)] = r[0];
    q[static_cast<size_t>(span + times - j - s)] = r[static_cast<size_t>(p - j - s)];
  }
  for (int i = l + 1; i < span - s; ++i) q[static_cast<size_t>(i)] = r[static_cast<size_t>(i - l)];
  *new_knots = k.knots();
  new_knots->insert(new_knots->begin() + span + 1, static_cast<size_t>(times), t);
  return q;
}

void CheckInsertion(const KnotVector& k, double t, int times) {
  if (!(t > k.domain_begin() && t < k.domain_end())) {
    std::ostringstream os;
    os << "knot insertion: t = " << t << " is not inside the domain (" << k.domain_begin() << ", "
       << k.domain_end() << ")";
    throw std::invalid_argument(os.str());
  }
  if (times < 1 || k.Multiplicity(t) + times > k.degree()) {
    std::ostringstream os;
    os << "knot insertion: inserting t = " << t << " " << times << " times would give multiplicity "
       << k.Multiplicity(t) + times << "; at most the degree " << k.degree() << " is allowed";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

template <int Dim>
NurbsCurve<Dim> InsertKnot(const NurbsCurve<Dim>& curve, double t, int times) {
  CheckInsertion(curve.knots(), t, times);
  std::vector<double> knots;
  auto q = BoehmInsert(curve.knots(), curve.weighted_points(), t, times, &knots);
  return NurbsCurve<Dim>::FromHomogeneous(KnotVector(curve.degree(), std::move(knots)),
                                          std::move(q));
}

NurbsSurface InsertKnot(const NurbsSurface& surface, Direction dir, double t, int times) {
  const bool in_u = dir == Direction::kU;
  const KnotVector& k = in_u ? surface.knots_u() : surface.knots_v();
  CheckInsertion(k, t, times);
  const int lines = in_u ? surface.num_v() : surface.num_u();
  const int n_new = k.num_basis() + times;
  const int nu = in_u ? n_new : surface.num_u();
  const int nv = in_u ? surface.num_v() : n_new;
  std::vector<Eigen::Vector4d> cpw(static_cast<size_t>(nu * nv));
  std::vector<double> knots;
  for (int line = 0; line < lines; ++line) {
    std::vector<Eigen::Vector4d> seq;
    for (int a = 0; a < k.num_basis(); ++a) {
      seq.push_back(in_u ? surface.weighted_point(a, line) : surface.weighted_point(line, a));
    }
    const auto q = BoehmInsert(k, seq, t, times, &knots);
    for (int a = 0; a < n_new; ++a) {
      const int i = in_u ? a : line;
      const int j = in_u ? line : a;
      cpw[static_cast<size_t>(i * nv + j)] = q[static_cast<size_t>(a)];
    }
  }
  KnotVector refined(k.degree(), std::move(knots));
  return NurbsSurface::FromHomogeneous(in_u ? refined : surface.knots_u(),
                                       in_u ? surface.knots_v() : refined, std::move(cpw));
}

namespace {}  // namespace

template <int Dim>
std::vector<NurbsCurve<Dim>> ExtractBezier(const NurbsCurve<Dim>& curve) {
  using HPoint = typename NurbsCurve<Dim>::HPoint;
  const KnotVector& k = curve.knots();
  const int p = k.degree();
  std::vector<NurbsCurve<Dim>> out;
  for (int mu : DomainSpans(k)) {
    std::vector<HPoint> net(static_cast<size_t>(p + 1));
    CurveBezierNet(k, curve.weighted_points(), mu, 0, net.data());
    out.push_back(NurbsCurve<Dim>::FromHomogeneous(
        KnotVector(p, ClampedBezierKnots(p, k[mu], k[mu + 1])), std::move(net)));
  }
  return out;
}

std::vector<NurbsSurface> ExtractBezier(const NurbsSurface& surface) {
  const KnotVector& ku = surface.knots_u();
  const KnotVector& kv = surface.knots_v();
  const int p = ku.degree();
  const int q = kv.degree();
  std::vector<NurbsSurface> out;
  for (int mu_u : DomainSpans(ku)) {
    for (int mu_v : DomainSpans(kv)) {
      std::vector<Eigen::Vector4d> net(static_cast<size_t>((p + 1) * (q + 1)));
      internal::SurfaceBezierNet(ku, kv, surface.weighted_points(), mu_u, mu_v, 0, 0, 1.0,
                                 net.data());
      out.push_back(NurbsSurface::FromHomogeneous(
          KnotVector(p, ClampedBezierKnots(p, ku[mu_u], ku[mu_u + 1])),
          KnotVector(q, ClampedBezierKnots(q, kv[mu_v], kv[mu_v + 1])), std::move(net)));
    }
  }
  return out;
}

namespace {

// Rows of the refined net's scaled differences at t in span mu: row a is
// p!/(p−a)! · (Δ^a Q)_0 / h^a with Q_i = b(t^{p−i}, e^i), i.e. the a-th derivative of the
// homogeneous piece, formed on the alpha rows with a δ arguments (no cancellation).
void DifferenceRows(const KnotVector& k, int mu, double t, int count, AlphaRow* rows) {
  const int p = k.degree();
  double x[kMaxDegree];
  for (int r = 0; r < p; ++r) x[r] = t;
  double factor = 1.0;
  for (int a = 0; a < count; ++a) {
    OsloAlphaRow(k, mu, x, &rows[a], a);
    for (int i = 0; i <= p; ++i) rows[a][static_cast<size_t>(i)] *= factor;
    factor *= p - a;
  }
}

}  // namespace

SurfacePoint EvaluateByRefinement(const NurbsSurface& surface, double u, double v, int order) {
  const KnotVector& ku = surface.knots_u();
  const KnotVector& kv = surface.knots_v();
  u = ku.Clamp(u);
  v = kv.Clamp(v);
  order = std::clamp(order, 0, kMaxOrder);
  const int p = ku.degree();
  const int q = kv.degree();
  const int mu_u = ku.FindSpan(u);
  const int mu_v = kv.FindSpan(v);
  const int na = std::min(order, p);
  const int nb = std::min(order, q);
  AlphaRow ru[kMaxOrder + 1], rv[kMaxOrder + 1];
  DifferenceRows(ku, mu_u, u, na + 1, ru);
  DifferenceRows(kv, mu_v, v, nb + 1, rv);
  // D[a][b] = ∂^{a+b} A / ∂u^a ∂v^b = Σ_i Σ_j ru[a][i] rv[b][j] P_ij, for a + b ≤ order.
  Eigen::Vector4d d[kMaxOrder + 1][kMaxOrder + 1];
  for (int a = 0; a <= kMaxOrder; ++a)
    for (int b = 0; b <= kMaxOrder; ++b) d[a][b].setZero();
  for (int a = 0; a <= na; ++a) {
    for (int b = 0; b <= nb && a + b <= order; ++b) {
      for (int i = 0; i <= p; ++i) {
        Eigen::Vector4d row = Eigen::Vector4d::Zero();
        for (int j = 0; j <= q; ++j) {
          row += rv[b][static_cast<size_t>(j)] * surface.weighted_point(mu_u - p + i, mu_v - q + j);
        }
        d[a][b] += ru[a][static_cast<size_t>(i)] * row;
      }
    }
  }
  HomogeneousSurfaceDerivs h;
  h.A[0] = d[0][0];
  h.A[1] = d[1][0];
  h.A[2] = d[0][1];
  h.A[3] = d[2][0];
  h.A[4] = d[1][1];
  h.A[5] = d[0][2];
  SurfacePoint out;
  RationalQuotient(h, order, &out);
  return out;
}

template <int Dim>
CurvePoint<Dim> EvaluateByRefinement(const NurbsCurve<Dim>& curve, double t, int order) {
  const KnotVector& k = curve.knots();
  t = k.Clamp(t);
  order = std::clamp(order, 0, kMaxOrder);
  const int p = k.degree();
  const int mu = k.FindSpan(t);
  const int na = std::min(order, p);
  AlphaRow rows[kMaxOrder + 1];
  DifferenceRows(k, mu, t, na + 1, rows);
  HomogeneousCurveDerivs<Dim> hd;
  for (int a = 0; a <= kMaxOrder; ++a) hd.A[a].setZero();
  for (int a = 0; a <= na; ++a) {
    for (int i = 0; i <= p; ++i) {
      hd.A[a] += rows[a][static_cast<size_t>(i)] *
                 curve.weighted_points()[static_cast<size_t>(mu - p + i)];
    }
  }
  CurvePoint<Dim> out;
  RationalQuotient(hd, order, &out);
  return out;
}

#define TANGENT_INSTANTIATE_CURVE_OPS(D)                                                \
  template NurbsCurve<D> RefineKnots(const NurbsCurve<D>&, const KnotVector&);          \
  template NurbsCurve<D> InsertKnot(const NurbsCurve<D>&, double, int);                 \
  template std::vector<NurbsCurve<D>> ExtractBezier(const NurbsCurve<D>&);              \
  template std::pair<NurbsCurve<D>, NurbsCurve<D>> Split(const NurbsCurve<D>&, double); \
  template CurvePoint<D> EvaluateByRefinement(const NurbsCurve<D>&, double, int);
TANGENT_INSTANTIATE_CURVE_OPS(2)
TANGENT_INSTANTIATE_CURVE_OPS(3)
#undef TANGENT_INSTANTIATE_CURVE_OPS

}  // namespace tangent::nurbs
