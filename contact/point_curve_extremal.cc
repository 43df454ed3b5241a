// The point–surface and curve–surface extremal solvers (contact/extremal.h): the same box solve
// as the surface pairs' (contact/solve_on_box.h) on two and three parameters.

#include <algorithm>
#include <limits>

#include "contact/box_newton.h"
#include "contact/extremal.h"
#include "contact/poles.h"
#include "contact/solve_on_box.h"
#include "contact/solver_inputs.h"

namespace tangent::contact {

namespace {

using internal::BestDeparture;
using internal::FindPoleRow;
using internal::PoleAction;
using internal::PoleIsMinimum;
using internal::PoleRow;

using internal::BoxOptionsOf;
using internal::KindAt;
using internal::SolveOnBox;
using internal::StatusOf;

using internal::FinitePose;
using internal::FirstFormScale;
using internal::Hi;
using internal::InvalidExtremum;
using internal::Lo;
using internal::SaneSeed;

}  // namespace

PointSurfaceExtremum SolvePointSurface(const Eigen::Vector3d& x_W, const nurbs::NurbsSurface& f,
                                       const BodyPose& pose_f, const Eigen::Vector2d& seed,
                                       const ExtremalOptions& options,
                                       PlacedSurfacePoint* at_solution) {
  if (!seed.allFinite() || !x_W.allFinite() || !FinitePose(pose_f)) {
    auto out = InvalidExtremum<PointSurfaceExtremum, 2>(SaneSeed<2>(seed, Lo(f), Hi(f)));
    out.distance = std::numeric_limits<double>::infinity();
    return out;
  }
  nurbs::SpanHint hf;
  PlacedSurfacePoint p;
  auto eval = [&](const Eigen::Vector2d& x, internal::NewtonSystem<2>* s) {
    EvaluatePlaced(f, pose_f, x[0], x[1], &hf, &p);
    const nurbs::SurfacePoint& a = p.world;
    const Eigen::Vector3d d = a.S - x_W;
    s->value = 0.5 * d.squaredNorm();
    s->grad << d.dot(a.S_u), d.dot(a.S_v);
    s->hess << a.S_u.dot(a.S_u) + d.dot(a.S_uu), a.S_u.dot(a.S_v) + d.dot(a.S_uv),
        a.S_u.dot(a.S_v) + d.dot(a.S_uv), a.S_v.dot(a.S_v) + d.dot(a.S_vv);
    s->F = s->grad;  // Regular at d = 0 already: one system inside and on the boundary.
    s->J = s->hess;
    s->scale = FirstFormScale(a);
    s->classify_scale = s->scale;
    s->penetrating = false;  // a point's nearest surface point is a minimum on either side
  };
  auto opt = BoxOptionsOf<2>(options);
  opt.periodic = {f.periodic_u(), f.periodic_v()};
  auto pole = [&](const Eigen::Vector2d& x, Eigen::Vector2d* y) {
    const PoleRow row = FindPoleRow(f, x);
    if (!row.found) return PoleAction::kNone;
    *y = x;
    (*y)[row.across] = row.bound;
    const Eigen::Vector3d d = pose_f.Point(f.Evaluate((*y)[0], (*y)[1], 0).S) - x_W;
    double angle = 0.0;
    if (BestDeparture(f, pose_f, row, d, 1.0, &angle) < -1e-9 * d.norm()) {
      *y = internal::OffPole(f, row, angle);
      return PoleAction::kEscape;
    }
    // No first-order descent: the pole is the minimum, or a maximum or saddle of the distance,
    // left along the departure that lowers it to second order.
    if (PoleIsMinimum(f, pose_f, row, x_W, &angle)) return PoleAction::kExtremum;
    *y = internal::OffPole(f, row, angle);
    return PoleAction::kEscape;
  };
  internal::NewtonSystem<2> s;
  const auto r = SolveOnBox<2>(eval, pole, seed, Lo(f), Hi(f), opt, options.seek, &s);
  PointSurfaceExtremum out;
  out.u = r.x;
  out.p_f = p.world.S;
  out.R_WCf = ContactFrame(p);
  const Eigen::Vector3d d = x_W - p.world.S;
  out.distance = d.dot(out.R_WCf.col(2));
  if (std::any_of(r.active.begin(), r.active.end(), [](bool b) { return b; })) {
    // Side by f's normal (x outside: positive), |x − f| in size.
    out.distance = (out.distance < 0.0 ? -1.0 : 1.0) * d.norm();
  }
  out.status = StatusOf(r);
  out.kind = KindAt<2>(r, s, Lo(f), Hi(f));
  out.at_bound = r.active;
  out.iterations = r.iterations;
  if (at_solution) *at_solution = p;
  return out;
}

void EvaluateCurveSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f, const BodyCurve& g,
                          const BodyPose& pose_g, const Eigen::Vector3d& u, nurbs::SpanHint* hint_f,
                          int* span_g, nurbs::SpanHint* hint_g, CurveSurfaceEval* out) {
  EvaluatePlaced(f, pose_f, u[0], u[1], hint_f, &out->f);
  EvaluatePlaced(g, pose_g, u[2], span_g, hint_g, &out->g);
  const nurbs::SurfacePoint& a = out->f.world;
  const nurbs::CurvePoint<3>& c = out->g.world;
  const Eigen::Vector3d& N = out->f.N_W;
  const Eigen::Vector3d d = c.C - a.S;
  out->d = d;
  out->F << d.dot(a.S_u), d.dot(a.S_v), N.dot(c.C1);
  out->F_u << -a.S_u.dot(a.S_u) + d.dot(a.S_uu), -a.S_v.dot(a.S_u) + d.dot(a.S_uv),
      c.C1.dot(a.S_u),                                                                        //
      -a.S_u.dot(a.S_v) + d.dot(a.S_uv), -a.S_v.dot(a.S_v) + d.dot(a.S_vv), c.C1.dot(a.S_v),  //
      out->f.N_W_u.dot(c.C1), out->f.N_W_v.dot(c.C1), N.dot(c.C2);
  out->grad << -d.dot(a.S_u), -d.dot(a.S_v), d.dot(c.C1);
  Eigen::Matrix3d& H = out->hess;
  H(0, 0) = a.S_u.dot(a.S_u) - d.dot(a.S_uu);
  H(0, 1) = a.S_u.dot(a.S_v) - d.dot(a.S_uv);
  H(1, 1) = a.S_v.dot(a.S_v) - d.dot(a.S_vv);
  H(0, 2) = -a.S_u.dot(c.C1);
  H(1, 2) = -a.S_v.dot(c.C1);
  H(2, 2) = c.C1.dot(c.C1) + d.dot(c.C2);
  H.triangularView<Eigen::StrictlyLower>() = H.transpose();
}

CurveSurfaceExtremum SolveCurveSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                       const BodyCurve& g, const BodyPose& pose_g,
                                       const Eigen::Vector3d& seed,
                                       const ExtremalOptions& options) {
  if (!seed.allFinite() || !FinitePose(pose_f) || !FinitePose(pose_g)) {
    Eigen::Vector3d lo, hi;
    lo << Lo(f), g.domain_begin();
    hi << Hi(f), g.domain_end();
    auto out = InvalidExtremum<CurveSurfaceExtremum, 3>(SaneSeed<3>(seed, lo, hi));
    out.beta = std::numeric_limits<double>::infinity();
    out.p_g.setZero();
    return out;
  }
  nurbs::SpanHint hf, hg;
  int span_g = 0;
  CurveSurfaceEval e;
  auto eval = [&](const Eigen::Vector3d& x, internal::NewtonSystem<3>* s) {
    EvaluateCurveSurface(f, pose_f, g, pose_g, x, &hf, &span_g, &hg, &e);
    s->value = 0.5 * e.d.squaredNorm();
    s->F = e.F;
    s->J = e.F_u;
    s->grad = e.grad;
    s->hess = e.hess;
    s->classify_scale = std::max(FirstFormScale(e.f.world), e.g.world.C1.squaredNorm());
    s->penetrating = e.d.dot(e.f.N_W) < 0.0;
  };
  Eigen::Vector3d lo, hi;
  lo << Lo(f), g.domain_begin();
  hi << Hi(f), g.domain_end();
  auto opt = BoxOptionsOf<3>(options);
  opt.periodic = {f.periodic_u(), f.periodic_v(), g.periodic()};
  internal::NewtonSystem<3> sys;
  // Poles of f against a curve are not handled yet (the pair and point solvers handle them).
  auto no_pole = [](const Eigen::Vector3d&, Eigen::Vector3d*) { return PoleAction::kNone; };
  const auto r = SolveOnBox<3>(eval, no_pole, seed, lo, hi, opt, options.seek, &sys);
  CurveSurfaceExtremum out;
  out.u = r.x;
  out.p_f = e.f.world.S;
  out.p_g = e.g.world.C;
  out.R_WCf = ContactFrame(e.f);
  out.beta = e.d.dot(out.R_WCf.col(2));
  if (std::any_of(r.active.begin(), r.active.end(), [](bool b) { return b; })) {
    out.beta = (out.beta < 0.0 ? -1.0 : 1.0) * e.d.norm();
  }
  out.status = StatusOf(r);
  out.kind = KindAt<3>(r, sys, lo, hi);
  out.at_bound = r.active;
  out.iterations = r.iterations;
  return out;
}

}  // namespace tangent::contact
