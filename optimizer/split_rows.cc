// The rows of a split contact (docs/contact.md, "Rows that stay on their minimum"): a row whose
// evaluation ended on the saddle between two minima, or on the other minimum, taken back to its
// own. Split from contacts.cc by concept.

#include "optimizer/split_rows.h"

#include <algorithm>
#include <cmath>

#include "contact/box_newton.h"
#include "contact/solver_inputs.h"

namespace tangent::optimizer::internal {

using contact::BodyPose;

namespace {

// to − from, periodic directions the short way round.
Eigen::Vector4d ShortWay(const contact::internal::PairBox& box, const Eigen::Vector4d& from,
                         const Eigen::Vector4d& to) {
  Eigen::Vector4d d = to - from;
  for (int i = 0; i < 4; ++i) {
    if (!box.periodic[static_cast<size_t>(i)]) continue;
    const double w = box.hi[i] - box.lo[i];
    d[i] -= w * std::round(d[i] / w);
  }
  return d;
}

// The point-surface distance from f's point at x's first two parameters to g, from x's last two
// (the height of the distance over f's parameters); +inf when that solve does not converge.
double HeightAt(const nurbs::NurbsSurface& f, const BodyPose& pf, const nurbs::NurbsSurface& g,
                const BodyPose& pg, const Eigen::Vector4d& x) {
  const Eigen::Vector3d p_W = pf.Point(f.Evaluate(x[0], x[1], 0).S);
  const contact::PointSurfaceExtremum q = contact::SolvePointSurface(p_W, g, pg, x.tail<2>());
  return q.status == contact::ExtremalStatus::kConverged ? q.distance : INFINITY;
}

}  // namespace

// contact::MinimumBesideSaddle on the side of `toward` (periodic directions the short way
// round), lower than the saddle.
bool MinimumToward(const nurbs::NurbsSurface& f, const BodyPose& pf, const nurbs::NurbsSurface& g,
                   const BodyPose& pg, const contact::SurfaceSurfaceExtremum& saddle,
                   const contact::SurfacePairEval& at, const contact::RelativeCurvature& rc,
                   const Eigen::Vector4d& toward, contact::SurfaceSurfaceExtremum* out,
                   contact::SurfacePairEval* out_eval) {
  const Eigen::Vector4d step = contact::ParameterStepAlong(at, rc.min_direction);
  const Eigen::Vector4d diff = ShortWay(contact::internal::PairBoxOf(f, g), saddle.u, toward);
  const double side = diff.dot(step) >= 0.0 ? 1.0 : -1.0;
  return contact::MinimumBesideSaddle(f, pf, g, pg, saddle, at, rc, side, out, out_eval) &&
         out->beta < saddle.beta;
}

// A row of a split pair (one minimum either side of a saddle) whose evaluation converged to a
// minimum `across` the saddle from its own: Newton, from beside the saddle, stepped into the
// other minimum's basin. Told by the distance over the row's last parameters `from` (at the
// same poses): `across` higher than it (a descent from `from` never ends higher), or a hump on
// the segment between them (samples at a quarter, half and three quarters higher than both
// ends). Then samples on the line from `across` through `from` and beyond it (periodic
// directions the short way round) find the lowest point on `from`'s side, and Newton from there
// must converge to a facing minimum no higher than `from` and nearer it than `across`.
// @return whether one was found (*out, *out_eval); false too when nothing shows a crossing.
bool MinimumOnOwnSide(const nurbs::NurbsSurface& f, const BodyPose& pf,
                      const nurbs::NurbsSurface& g, const BodyPose& pg,
                      const contact::SurfaceSurfaceExtremum& across, const Eigen::Vector4d& from,
                      contact::SurfaceSurfaceExtremum* out, contact::SurfacePairEval* out_eval) {
  const contact::internal::PairBox box = contact::internal::PairBoxOf(f, g);
  const Eigen::Vector4d diff = ShortWay(box, across.u, from);
  auto at = [&](double t) {
    return contact::internal::ClampOrWrap<4>(across.u + t * diff, box.lo, box.hi, box.periodic);
  };
  const double near = HeightAt(f, pf, g, pg, at(1.0));
  // (Higher by more than the heights' rounding, ~1e-16 of the points' size.)
  const double tolerance = 1e-13 * (across.p_f.norm() + 1e-3);
  bool crossed = near < across.beta - tolerance;
  for (const double t : {0.25, 0.5, 0.75}) {
    if (crossed) break;
    crossed = HeightAt(f, pf, g, pg, at(t)) > std::max(near, across.beta) + tolerance;
  }
  if (!crossed) return false;
  Eigen::Vector4d best = at(1.0);
  double best_height = near;
  for (const double t : {1.25, 1.5, 2.0, 3.0}) {
    const double h = HeightAt(f, pf, g, pg, at(t));
    if (!(h < best_height)) break;
    best = at(t);
    best_height = h;
  }
  const contact::SurfaceSurfaceExtremum e =
      contact::SolveSurfaceSurface(f, pf, g, pg, best, contact::kContinuation, out_eval);
  if (e.status != contact::ExtremalStatus::kConverged || !(e.alignment < 0.0) ||
      !(e.beta <= near + tolerance) ||
      2.0 * contact::ParameterDistance(f, g, e.u, across.u) <
          contact::ParameterDistance(f, g, from, across.u)) {
    return false;
  }
  const contact::RelativeCurvature k = contact::RelativeCurvatureOf(*out_eval);
  if (!k.valid || k.crossing) return false;
  *out = e;
  return true;
}

}  // namespace tangent::optimizer::internal
