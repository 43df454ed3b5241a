#include "contact/charted_pair.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "contact/box_newton.h"
#include "contact/relative_curvature.h"
#include "contact/solver_inputs.h"

namespace tangent::contact {

namespace {

using internal::FirstFormScale;

}  // namespace

PairCharts FindPairCharts(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                          const Eigen::Vector4d& u, double fraction) {
  PairCharts c;
  nurbs::SpanHint hint;
  for (int k = 0; k < 2; ++k) {
    const nurbs::NurbsSurface& s = k == 0 ? f : g;
    const Eigen::Vector2d uv = u.segment<2>(2 * k);
    if (FindPoleChart(s, uv, fraction, &c.side[k]) && !ChartHolds(s, c.side[k], uv, &hint)) {
      c.side[k] = PoleChart{};
    }
    hint = {};
  }
  return c;
}

void EvaluatePairCharted(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                         const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                         const Eigen::Vector4d& u, const PairCharts& charts,
                         nurbs::SpanHint* hint_f, nurbs::SpanHint* hint_g, SurfacePairEval* out,
                         bool gradient_form) {
  if (charts.side[0].valid()) {
    EvaluateCharted(f, charts.side[0], pose_f, u.head<2>(), hint_f, &out->f);
  } else {
    EvaluatePlaced(f, pose_f, u[0], u[1], hint_f, &out->f);
  }
  if (charts.side[1].valid()) {
    EvaluateCharted(g, charts.side[1], pose_g, u.tail<2>(), hint_g, &out->g);
  } else {
    EvaluatePlaced(g, pose_g, u[2], u[3], hint_g, &out->g);
  }
  PairEquations(out, gradient_form);
}

bool SolveInCharts(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                   const nurbs::NurbsSurface& g, const BodyPose& pose_g, const PairCharts& charts,
                   const Eigen::Vector4d& seed, const ExtremalOptions& options,
                   SurfaceSurfaceExtremum* out, SurfacePairEval* at_solution) {
  if (!charts.any()) return false;
  const nurbs::NurbsSurface* surface[2] = {&f, &g};
  const internal::PairBox box = internal::PairBoxOf(f, g);
  const Eigen::Vector4d &lo = box.lo, &hi = box.hi;
  const std::array<bool, 4>& periodic = box.periodic;
  nurbs::SpanHint hint[2];
  Eigen::Vector4d u = internal::ClampOrWrap<4>(seed, lo, hi, periodic);
  // The unknowns: each charted side's chart coordinates, the other's parameters; and the size
  // a step is measured against (a parameter's domain width; a chart's: the pole's meridian,
  // |∂S/∂ρ| times the across width, so both read as fractions of the surface).
  Eigen::Vector4d x = u, size = hi - lo;
  for (int k = 0; k < 2; ++k) {
    const PoleChart& c = charts.side[k];
    if (!c.valid()) continue;
    x.segment<2>(2 * k) = ChartCoordinates(*surface[k], c, u.segment<2>(2 * k), &hint[k]);
    size.segment<2>(2 * k).setConstant(c.length);
  }
  SurfacePairEval& e = *at_solution;
  bool converged = false;
  int iterations = 0;
  for (; iterations < options.max_iterations && !converged; ++iterations) {
    EvaluatePairCharted(f, pose_f, g, pose_g, u, charts, &hint[0], &hint[1], &e,
                        /*gradient_form=*/false);
    const Eigen::PartialPivLU<Eigen::Matrix4d> lu(e.F_u);
    const Eigen::Vector4d step = -lu.solve(e.F);
    if (!step.allFinite()) return false;
    x += step;
    converged = step.cwiseQuotient(size).cwiseAbs().maxCoeff() <= options.step_tolerance;
    for (int k = 0; k < 2; ++k) {
      const PoleChart& c = charts.side[k];
      if (c.valid()) {
        Eigen::Vector2d uv;
        if (!ChartParameters(*surface[k], c, x.segment<2>(2 * k), u.segment<2>(2 * k), &hint[k],
                             &uv) ||
            c.Rho(uv) > kChartReach * c.width) {
          return false;  // left the chart's zone: the box solve's ground
        }
        u.segment<2>(2 * k) = uv;
        continue;
      }
      for (int i = 2 * k; i < 2 * k + 2; ++i) {
        if (periodic[static_cast<size_t>(i)]) continue;
        if (x[i] < lo[i] || x[i] > hi[i]) return false;  // a bound: the box solve's
      }
      u.segment<2>(2 * k) = x.segment<2>(2 * k);
    }
    u = internal::ClampOrWrap<4>(u, lo, hi, periodic);
    for (int k = 0; k < 2; ++k) {
      if (!charts.side[k].valid()) x.segment<2>(2 * k) = u.segment<2>(2 * k);
    }
  }
  if (!converged) return false;
  EvaluatePairCharted(f, pose_f, g, pose_g, u, charts, &hint[0], &hint[1], &e);
  const Eigen::PartialPivLU<Eigen::Matrix4d> lu(e.F_u);
  const double rcond = lu.rcond();
  const double size_pq = std::sqrt(std::max(FirstFormScale(e.f.world), FirstFormScale(e.g.world))) +
                         e.f.world.S.norm() + e.g.world.S.norm();
  const bool touching =
      e.d.norm() <= internal::kTouchingDistance * size_pq &&
      e.f.unit_normal().cross(e.g.unit_normal()).norm() <= internal::kTouchingSine;
  if (!touching && !(rcond > internal::kSingularRcond)) return false;
  ExtremumKind kind;
  if (touching) {
    kind = RelativeCurvatureOf(e).crossing ? ExtremumKind::kSaddle : ExtremumKind::kMinimum;
  } else {
    kind = internal::Classify<4>(e.hess, {},
                                 std::max(FirstFormScale(e.f.world), FirstFormScale(e.g.world)));
  }
  const bool penetrating = e.d.dot(e.g.N_W) < 0.0 && e.d.dot(e.f.N_W) > 0.0;
  if (options.seek == Seek::kMinimum && !touching && kind != ExtremumKind::kMinimum &&
      !penetrating) {
    return false;
  }
  internal::FillPairFields(e, u, out);
  out->status = ExtremalStatus::kConverged;
  out->kind = kind;
  out->at_bound = {};
  out->iterations = iterations;
  out->rcond = rcond;
  return true;
}

}  // namespace tangent::contact
