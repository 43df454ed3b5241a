#include "contact/extremal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "contact/box_newton.h"
#include "contact/charted_pair.h"
#include "contact/neighbourhood.h"
#include "contact/poles.h"
#include "contact/relative_curvature.h"
#include "contact/solve_on_box.h"
#include "contact/solver_inputs.h"

namespace tangent::contact {

const char* ToString(ExtremalStatus s) {
  switch (s) {
    case ExtremalStatus::kConverged:
      return "converged";
    case ExtremalStatus::kAtBoundary:
      return "at_boundary";
    case ExtremalStatus::kSingular:
      return "singular";
    case ExtremalStatus::kNotConverged:
      return "not_converged";
    case ExtremalStatus::kInvalidInput:
      return "invalid_input";
  }
  return "?";
}

const char* ToString(ExtremumKind k) {
  switch (k) {
    case ExtremumKind::kMinimum:
      return "minimum";
    case ExtremumKind::kSaddle:
      return "saddle";
    case ExtremumKind::kMaximum:
      return "maximum";
    case ExtremumKind::kDegenerate:
      return "degenerate";
  }
  return "?";
}

double BoundarySide(const Eigen::Vector3d& d, const Eigen::Vector3d& n_f,
                    const Eigen::Vector3d& n_g) {
  const double nf = n_f.norm(), ng = n_g.norm();
  const double along_g = ng > 0.0 ? d.dot(n_g) / ng : 0.0;
  const double along_f = nf > 0.0 ? d.dot(n_f) / nf : 0.0;
  const double side = std::abs(along_g) >= std::abs(along_f) ? along_g : -along_f;
  return side < 0.0 ? -1.0 : 1.0;
}

namespace internal {

template <int N>
ExtremumKind Classify(const Eigen::Matrix<double, N, N>& hess, const std::array<bool, N>& active,
                      double scale) {
  // Inertia of the Hessian on the free parameters (Sylvester's law: the signs of D in a pivoted
  // LDLᵀ are those of the eigenvalues; a few times cheaper than an eigen-decomposition). Pivots
  // below 1e-6 of the natural scale count as zero: near a focal point (where the Hessian
  // vanishes) the iterate stops ~1e-8 away and the pivots are that small; the same bar absorbs
  // the rank-2 degeneracy of touching pairs.
  Eigen::Matrix<double, N, N> h = hess;
  for (int i = 0; i < N; ++i) {
    if (!active[static_cast<size_t>(i)]) continue;
    h.row(i).setZero();
    h.col(i).setZero();
  }
  const Eigen::LDLT<Eigen::Matrix<double, N, N>> ldlt(h);
  const auto d = ldlt.vectorD();
  const double tol = 1e-6 * std::max(scale, d.cwiseAbs().maxCoeff());
  int pos = 0, neg = 0;
  for (int i = 0; i < N; ++i) {
    pos += d[i] > tol;
    neg += d[i] < -tol;
  }
  if (pos > 0 && neg > 0) return ExtremumKind::kSaddle;
  if (pos > 0) return ExtremumKind::kMinimum;
  if (neg > 0) return ExtremumKind::kMaximum;
  return ExtremumKind::kDegenerate;
}

template ExtremumKind Classify<2>(const Eigen::Matrix2d&, const std::array<bool, 2>&, double);
template ExtremumKind Classify<3>(const Eigen::Matrix3d&, const std::array<bool, 3>&, double);
template ExtremumKind Classify<4>(const Eigen::Matrix4d&, const std::array<bool, 4>&, double);

}  // namespace internal

void EvaluatePair(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                  const nurbs::NurbsSurface& g, const BodyPose& pose_g, const Eigen::Vector4d& u,
                  nurbs::SpanHint* hint_f, nurbs::SpanHint* hint_g, SurfacePairEval* out,
                  bool gradient_form) {
  EvaluatePlaced(f, pose_f, u[0], u[1], hint_f, &out->f);
  EvaluatePlaced(g, pose_g, u[2], u[3], hint_g, &out->g);
  PairEquations(out, gradient_form);
}

void PairEquations(SurfacePairEval* out, bool gradient_form) {
  const nurbs::SurfacePoint& a = out->f.world;
  const nurbs::SurfacePoint& b = out->g.world;
  const Eigen::Vector3d& N = out->f.N_W;
  const Eigen::Vector3d d = a.S - b.S;
  out->d = d;
  out->F << d.dot(b.S_u), d.dot(b.S_v), N.dot(b.S_u), N.dot(b.S_v);
  Eigen::Matrix4d& J = out->F_u;
  J << a.S_u.dot(b.S_u), a.S_v.dot(b.S_u), -b.S_u.dot(b.S_u) + d.dot(b.S_uu),
      -b.S_v.dot(b.S_u) + d.dot(b.S_uv),  //
      a.S_u.dot(b.S_v), a.S_v.dot(b.S_v), -b.S_u.dot(b.S_v) + d.dot(b.S_uv),
      -b.S_v.dot(b.S_v) + d.dot(b.S_vv),                                               //
      out->f.N_W_u.dot(b.S_u), out->f.N_W_v.dot(b.S_u), N.dot(b.S_uu), N.dot(b.S_uv),  //
      out->f.N_W_u.dot(b.S_v), out->f.N_W_v.dot(b.S_v), N.dot(b.S_uv), N.dot(b.S_vv);
  if (gradient_form) FillGradientForm(out);
}

void FillGradientForm(SurfacePairEval* out) {
  const nurbs::SurfacePoint& a = out->f.world;
  const nurbs::SurfacePoint& b = out->g.world;
  const Eigen::Vector3d& d = out->d;
  out->grad << d.dot(a.S_u), d.dot(a.S_v), -d.dot(b.S_u), -d.dot(b.S_v);
  Eigen::Matrix4d& H = out->hess;
  H(0, 0) = a.S_u.dot(a.S_u) + d.dot(a.S_uu);
  H(0, 1) = a.S_u.dot(a.S_v) + d.dot(a.S_uv);
  H(1, 1) = a.S_v.dot(a.S_v) + d.dot(a.S_vv);
  H(0, 2) = -a.S_u.dot(b.S_u);
  H(0, 3) = -a.S_u.dot(b.S_v);
  H(1, 2) = -a.S_v.dot(b.S_u);
  H(1, 3) = -a.S_v.dot(b.S_v);
  H(2, 2) = b.S_u.dot(b.S_u) - d.dot(b.S_uu);
  H(2, 3) = b.S_u.dot(b.S_v) - d.dot(b.S_uv);
  H(3, 3) = b.S_v.dot(b.S_v) - d.dot(b.S_vv);
  H.triangularView<Eigen::StrictlyLower>() = H.transpose();
}

namespace {

using internal::BestDeparture;
using internal::FindPoleRow;
using internal::PoleAction;
using internal::PoleIsMinimum;
using internal::PoleRow;

using internal::Acceptable;
using internal::BoxOptionsOf;
using internal::IsBoxMinimum;
using internal::IsPenetration;
using internal::KindAt;
using internal::SolveOnBox;
using internal::StatusOf;

using internal::FinitePose;
using internal::FirstFormScale;
using internal::Hi;
using internal::InvalidExtremum;
using internal::Lo;
using internal::SaneSeed;

// NewtonSystem::touching for a surface pair at parameters x (limit normals at poles: a dome
// touched at its pole is the common case). Off a pole the points must coincide to rounding
// (kTouchingDistance): along the tangent plane a touching pair is fixed only to sqrt(2 R |d|).
// On a pole row the pair is re-made exactly by the pole's own answer (SolveOnBox: the pole
// point and its foot), so there a gap within the servo's hold of an active contact counts: such
// a pair, nearly singular twice over (β ≈ 0 and the pole), otherwise took 500 iterations.
constexpr double kTouchingAtPole = 1e-9;
bool Touching(const SurfacePairEval& e, double first_form_scale, const nurbs::NurbsSurface& f,
              const nurbs::NurbsSurface& g, const Eigen::Vector4d& x) {
  const double size = std::sqrt(first_form_scale) + e.f.world.S.norm() + e.g.world.S.norm();
  const double dist = e.d.norm();
  if (!(dist <= kTouchingAtPole * size)) return false;
  if (!(e.f.unit_normal().cross(e.g.unit_normal()).norm() <= internal::kTouchingSine)) {
    return false;
  }
  if (dist <= internal::kTouchingDistance * size) return true;
  return FindPoleRow(f, x.head<2>()).found || FindPoleRow(g, x.tail<2>()).found;
}

}  // namespace

namespace internal {

void FillPairFields(const SurfacePairEval& e, const Eigen::Vector4d& u,
                    SurfaceSurfaceExtremum* out) {
  out->u = u;
  out->p_f = e.f.world.S;
  out->p_g = e.g.world.S;
  out->R_WCf = ContactFrame(e.f);
  out->R_WCg = ContactFrame(e.g);
  out->n_g = out->R_WCg.col(2);
  out->direction = out->n_g;
  out->beta = e.d.dot(out->n_g);
  out->alignment = out->R_WCf.col(2).dot(out->n_g);
}

}  // namespace internal

using internal::FillPairFields;

double ScaledContactResidual(const SurfacePairEval& e, double beta) {
  const double len_g =
      std::sqrt(std::max(e.g.world.S_u.squaredNorm(), e.g.world.S_v.squaredNorm()));
  return std::max(std::max(std::abs(e.F[0]), std::abs(e.F[1])) /
                      (len_g * std::max(std::abs(beta), 1e-3 * len_g)),
                  std::max(std::abs(e.F[2]), std::abs(e.F[3])) / (e.f.N_W.norm() * len_g));
}

namespace {

// A pair whose point on one surface is a vertex pole (IsVertex): on which surface, and whether
// the pole is a minimum of the distance to the other point.
struct VertexPole {
  bool found = false;
  bool on_f = true;
  bool minimum = false;
};
VertexPole VertexAt(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                    const nurbs::NurbsSurface& g, const BodyPose& pose_g, const Eigen::Vector4d& x,
                    const SurfacePairEval& e) {
  VertexPole out;
  for (int k = 0; k < 2; ++k) {
    const nurbs::NurbsSurface& s = k == 0 ? f : g;
    const Eigen::Vector2d uv = x.segment<2>(2 * k);
    const PoleRow row = FindPoleRow(s, uv);
    // On the row, or within rounding of it (Newton on F stops ~1e-13 from a pole it is singular
    // at, as in a pressed apex's penetration extremum).
    const nurbs::KnotVector& k_across = row.across == 1 ? s.knots_v() : s.knots_u();
    const double width = k_across.domain_end() - k_across.domain_begin();
    if (!row.found || std::abs(uv[row.across] - row.bound) > 1e-9 * width ||
        !internal::IsVertex(s, row)) {
      continue;
    }
    out.found = true;
    out.on_f = k == 0;
    out.minimum = k == 0 ? PoleIsMinimum(f, pose_f, row, e.g.world.S)
                         : PoleIsMinimum(g, pose_g, row, e.f.world.S);
    return out;
  }
  return out;
}

// The neighbourhood search of ExtremalOptions::neighbourhood: SolveOnBox from each start of the
// seed's neighbourhood (its edges' and corners' closest samples), and the
// nearest box minimum apart among them and the seed's own answer *r (at *sys, *e) replaces it.
// A start's answer must be nearer by more than rounding: the same minimum found again keeps the
// seed's answer.
template <class Eval, class Pole>
void NearestInNeighbourhood(Eval& eval, Pole& pole, const nurbs::NurbsSurface& f,
                            const BodyPose& pose_f, const nurbs::NurbsSurface& g,
                            const BodyPose& pose_g, const Eigen::Vector4d& seed,
                            const Eigen::Vector4d& lo, const Eigen::Vector4d& hi,
                            const internal::BoxNewtonOptions<4>& opt,
                            const ExtremalOptions& options, internal::BoxNewtonResult<4>* r,
                            internal::NewtonSystem<4>* sys, SurfacePairEval* e) {
  internal::NeighbourhoodStarts starts;
  internal::FindNeighbourhoodStarts(f, pose_f, g, pose_g,
                                    internal::ClampOrWrap<4>(seed, lo, hi, opt.periodic),
                                    options.neighbourhood, &starts);
  if (starts.n == 0) return;
  const bool answered = IsBoxMinimum<4>(*r, *sys, lo, hi);
  double nearest = answered ? std::sqrt(2.0 * sys->value) : std::numeric_limits<double>::infinity();
  int iterations = r->iterations;
  internal::BoxNewtonResult<4> best = *r;
  internal::NewtonSystem<4> best_sys = *sys;
  SurfacePairEval best_e = *e;
  for (int k = 0; k < starts.n; ++k) {
    internal::NewtonSystem<4> s;
    const internal::BoxNewtonResult<4> c = SolveOnBox<4>(
        eval, pole, starts.u[static_cast<size_t>(k)], lo, hi, opt, Seek::kMinimum, &s);
    iterations += c.iterations;
    const bool minimum = s.touching ? c.converged : IsBoxMinimum<4>(c, s, lo, hi);
    const double distance = std::sqrt(2.0 * s.value);
    if (!minimum || IsPenetration<4>(c, s) || !(distance < nearest * (1.0 - 1e-12))) continue;
    nearest = distance;
    best = c;
    best_sys = s;
    best_e = *e;  // the evaluation at c.x (SolveOnBox's contract)
  }
  *r = best;
  r->iterations = iterations;
  *sys = best_sys;
  *e = best_e;
}

}  // namespace

SurfaceSurfaceExtremum SolveSurfaceSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                           const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                                           const Eigen::Vector4d& seed,
                                           const ExtremalOptions& options,
                                           SurfacePairEval* at_solution) {
  if (!seed.allFinite() || !FinitePose(pose_f) || !FinitePose(pose_g)) {
    const internal::PairBox box = internal::PairBoxOf(f, g);
    auto out = InvalidExtremum<SurfaceSurfaceExtremum, 4>(SaneSeed<4>(seed, box.lo, box.hi));
    out.beta = std::numeric_limits<double>::infinity();
    out.p_g.setZero();
    out.n_g = Eigen::Vector3d::UnitZ();
    out.direction = out.n_g;
    out.R_WCg.setIdentity();
    out.alignment = -1.0;
    return out;
  }
  // A continued extremum next to a smooth pole: Newton in the pole's chart, where it is as
  // regular as anywhere (in (u, v) it is singular at the pole and only linear near it).
  SurfaceSurfaceExtremum charted;
  SurfacePairEval charted_e;
  if (options.neighbourhood == 0.0) {
    const PairCharts charts = FindPairCharts(f, g, IntoPairDomain(f, g, seed), kChartSolve);
    if (charts.any() &&
        SolveInCharts(f, pose_f, g, pose_g, charts, seed, options, &charted, &charted_e)) {
      if (at_solution) *at_solution = charted_e;
      return charted;
    }
  }
  nurbs::SpanHint hf, hg;
  SurfacePairEval e;
  auto eval = [&](const Eigen::Vector4d& x, internal::NewtonSystem<4>* s) {
    EvaluatePair(f, pose_f, g, pose_g, x, &hf, &hg, &e);
    s->value = 0.5 * e.d.squaredNorm();
    s->F = e.F;
    s->J = e.F_u;
    s->grad = e.grad;
    s->hess = e.hess;
    s->classify_scale = std::max(FirstFormScale(e.f.world), FirstFormScale(e.g.world));
    // Each inside the other (facing normals): not a spurious saddle of a separated pair.
    s->penetrating = e.d.dot(e.g.N_W) < 0.0 && e.d.dot(e.f.N_W) > 0.0;
    s->touching = Touching(e, s->classify_scale, f, g, x);
  };
  const internal::PairBox box = internal::PairBoxOf(f, g);
  const Eigen::Vector4d& lo = box.lo;
  const Eigen::Vector4d& hi = box.hi;
  auto opt = BoxOptionsOf<4>(options);
  opt.periodic = box.periodic;
  auto pole = [&](const Eigen::Vector4d& x, Eigen::Vector4d* y) {
    for (int side = 0; side < 2; ++side) {
      const nurbs::NurbsSurface& s = side == 0 ? f : g;
      const nurbs::NurbsSurface& o = side == 0 ? g : f;
      const BodyPose& ps = side == 0 ? pose_f : pose_g;
      const BodyPose& po = side == 0 ? pose_g : pose_f;
      const Eigen::Vector2d uv = x.segment<2>(2 * side);
      const PoleRow row = FindPoleRow(s, uv);
      if (!row.found) continue;
      Eigen::Vector2d at = uv;
      at[row.across] = row.bound;
      const Eigen::Vector3d P = ps.Point(s.Evaluate(at[0], at[1], 0).S);
      const PointSurfaceExtremum q =
          SolvePointSurface(P, o, po, x.segment<2>(2 * (1 - side)), options);
      if (q.status == ExtremalStatus::kInvalidInput) return PoleAction::kNone;
      const Eigen::Vector3d d = side == 0 ? Eigen::Vector3d(P - q.p_f) : Eigen::Vector3d(q.p_f - P);
      *y = x;
      y->segment<2>(2 * side) = at;
      y->segment<2>(2 * (1 - side)) = q.u;
      double angle = 0.0;
      // Touching at the pole (d at rounding level, its direction noise): no departure to take.
      const bool touching = d.norm() <= internal::kTouchingDistance * (P.norm() + q.p_f.norm());
      if (!touching &&
          BestDeparture(s, ps, row, d, side == 0 ? 1.0 : -1.0, &angle) < -1e-9 * d.norm()) {
        y->segment<2>(2 * side) = internal::OffPole(s, row, angle);
        return PoleAction::kEscape;
      }
      // No first-order descent: the pole is the minimum, or a maximum or saddle of the
      // distance, left along the departure that lowers it to second order.
      if (!PoleIsMinimum(s, ps, row, q.p_f, &angle)) {
        if (touching) return PoleAction::kNone;
        y->segment<2>(2 * side) = internal::OffPole(s, row, angle);
        return PoleAction::kEscape;
      }
      return q.kind == ExtremumKind::kMinimum ? PoleAction::kExtremum : PoleAction::kNone;
    }
    return PoleAction::kNone;
  };
  internal::NewtonSystem<4> sys;
  auto r = SolveOnBox<4>(eval, pole, seed, lo, hi, opt, options.seek, &sys);
  // e is the pair at r.x (SolveOnBox's contract).
  if (options.seek == Seek::kMinimum && options.neighbourhood > 0.0 && !sys.touching &&
      !IsPenetration<4>(r, sys)) {
    NearestInNeighbourhood(eval, pole, f, pose_f, g, pose_g, seed, lo, hi, opt, options, &r, &sys,
                           &e);
  }
  SurfaceSurfaceExtremum out;
  FillPairFields(e, r.x, &out);
  out.at_bound = r.active;
  const double dist = e.d.norm();
  if (std::any_of(r.active.begin(), r.active.end(), [](bool b) { return b; }) && dist > 0.0) {
    const double side = BoundarySide(e.d, out.R_WCf.col(2), out.R_WCg.col(2));
    out.direction = side * (e.d / dist);
    out.beta = side * dist;
  }
  out.status = StatusOf(r);
  // At a vertex (a cone's apex) the answer is the pole itself (SolveOnBox), and that surface has
  // no normal there: β is measured along the other surface's normal (the vertex's foot on it is
  // along that normal, touching and pressed in too), or, where the other point is held on a
  // boundary, along d as at a boundary; the kind is the pole's own second-order test.
  if (const VertexPole v = VertexAt(f, pose_f, g, pose_g, r.x, e); v.found) {
    const bool other_held = v.on_f ? (r.active[2] || r.active[3]) : (r.active[0] || r.active[1]);
    if (other_held && dist > 0.0) {
      const double side = v.on_f ? (e.d.dot(e.g.unit_normal()) < 0.0 ? -1.0 : 1.0)
                                 : (e.d.dot(e.f.unit_normal()) > 0.0 ? -1.0 : 1.0);
      out.direction = side * (e.d / dist);
    } else {
      out.direction = v.on_f ? e.g.unit_normal() : Eigen::Vector3d(-e.f.unit_normal());
    }
    out.beta = e.d.dot(out.direction);
    out.kind = v.minimum ? ExtremumKind::kMinimum : ExtremumKind::kSaddle;
    out.iterations = r.iterations;
    out.rcond = r.rcond;
    if (at_solution) *at_solution = e;
    return out;
  }
  // An answer next to a smooth pole that Newton in (u, v) did not finish (it is only linear
  // there): finished in the pole's chart.
  if (out.status == ExtremalStatus::kNotConverged || out.status == ExtremalStatus::kSingular) {
    const PairCharts charts = FindPairCharts(f, g, r.x, kChartSolve);
    if (charts.any() &&
        SolveInCharts(f, pose_f, g, pose_g, charts, r.x, options, &charted, &charted_e)) {
      charted.iterations += r.iterations;
      if (at_solution) *at_solution = charted_e;
      return charted;
    }
  }
  // Touching: the Hessian of ½|d|² is singular there (rank 2), so the relative curvature
  // decides: the surfaces on either side of the tangent plane (a minimum of the distance, zero),
  // or crossing near the point (a saddle: β ≥ 0 there would let them interpenetrate off it).
  if (sys.touching && r.converged) {
    out.kind = RelativeCurvatureOf(e).crossing ? ExtremumKind::kSaddle : ExtremumKind::kMinimum;
  } else {
    out.kind = KindAt<4>(r, sys, lo, hi);
  }
  out.iterations = r.iterations;
  out.rcond = r.rcond;
  if (at_solution) *at_solution = e;
  return out;
}

double ParameterDistance(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                         const Eigen::Vector4d& x, const Eigen::Vector4d& y) {
  const nurbs::NurbsSurface* s[4] = {&f, &f, &g, &g};
  double d = 0.0;
  for (int i = 0; i < 4; ++i) {
    const bool u_dir = i % 2 == 0;
    const auto& kv = u_dir ? s[i]->knots_u() : s[i]->knots_v();
    const double w = kv.domain_end() - kv.domain_begin();
    double e = std::abs(x[i] - y[i]);
    if (u_dir ? s[i]->periodic_u() : s[i]->periodic_v()) e = std::min(e, w - e);
    d = std::max(d, e / w);
  }
  return d;
}

bool FoundAnotherExtremum(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                          const Eigen::Vector4d& from, const SurfaceSurfaceExtremum& solved,
                          double held_distance) {
  // (Farther by more than rounding: on a pole the same point has any angle, and a touching pair's
  // β and |d| there differ by ~1e-19 m either way.)
  return ParameterDistance(f, g, from, solved.u) > kMaxResolveJump &&
         solved.beta > held_distance + kSamePointDistance;
}

SurfaceSurfaceExtremum ExtremumAt(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                                  const Eigen::Vector4d& u, double tolerance,
                                  SurfacePairEval* at_solution, const PairCharts* charts) {
  nurbs::SpanHint hf, hg;
  SurfacePairEval& e = *at_solution;
  if (charts && charts->any()) {
    EvaluatePairCharted(f, pose_f, g, pose_g, u, *charts, &hf, &hg, &e);
  } else {
    EvaluatePair(f, pose_f, g, pose_g, u, &hf, &hg, &e);
  }
  SurfaceSurfaceExtremum out;
  FillPairFields(e, u, &out);
  const double residual = ScaledContactResidual(e, out.beta);
  // Next to a pole the chart resolves the normal only so far (ChartPrecision).
  double floor = tolerance;
  for (int k = 0; charts && k < 2; ++k) {
    if (charts->side[k].valid()) {
      floor = std::max(floor, ChartPrecision(charts->side[k], u.segment<2>(2 * k)));
    }
  }
  out.status = residual <= floor ? ExtremalStatus::kConverged : ExtremalStatus::kNotConverged;
  out.kind = internal::Classify<4>(e.hess, {},
                                   std::max(FirstFormScale(e.f.world), FirstFormScale(e.g.world)));
  out.iterations = 0;
  return out;
}

Eigen::Vector4d IntoPairDomain(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                               const Eigen::Vector4d& u) {
  const internal::PairBox box = internal::PairBoxOf(f, g);
  return internal::ClampOrWrap<4>(u, box.lo, box.hi, box.periodic);
}

}  // namespace tangent::contact
