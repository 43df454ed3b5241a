#pragma once

// A surface pair with either point in its pole's chart (docs/contact.md, "Pole charts"): the
// contact equations F and their Jacobian in mixed coordinates, each charted side's point moved
// in its tangent-plane chart (x, y) and the other in its parameters. The equations are the
// same as EvaluatePair's (they use only points and partials), so near a smooth pole Newton on
// them is as regular as anywhere else.

#include <Eigen/Core>

#include "contact/extremal.h"
#include "contact/pole_chart.h"

namespace tangent::contact {

/// The charts a pair's two points are taken in (either, both or none).
struct PairCharts {
  PoleChart side[2];  ///< f's, g's; invalid (across −1) for a side in its parameters
  bool any() const { return side[0].valid() || side[1].valid(); }
};

/// The charts of the smooth poles within `fraction` of the domain from u's points.
PairCharts FindPairCharts(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                          const Eigen::Vector4d& u, double fraction);

/// EvaluatePair with each charted side evaluated in its chart (EvaluateCharted): the same
/// record, its partials, F_u and (with `gradient_form`) grad and hess in the mixed coordinates.
void EvaluatePairCharted(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                         const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                         const Eigen::Vector4d& u, const PairCharts& charts,
                         nurbs::SpanHint* hint_f, nurbs::SpanHint* hint_g, SurfacePairEval* out,
                         bool gradient_form = true);

/// Newton on the contact equations from `seed` (parameters) with the charted sides moved in
/// their charts. True, with *out (parameters in out->u) and *at_solution (in the mixed
/// coordinates), when it converges to the step tolerance to an interior extremum whose charted
/// points stayed within kChartReach of their poles and which `options.seek` accepts: under
/// Seek::kMinimum a minimum of the distance, a touching pair, or a penetration extremum. False
/// otherwise (a bound reached, a chart left, a singular matrix, the budget spent, another kind):
/// the caller's box solve then decides. Allocation free.
bool SolveInCharts(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                   const nurbs::NurbsSurface& g, const BodyPose& pose_g, const PairCharts& charts,
                   const Eigen::Vector4d& seed, const ExtremalOptions& options,
                   SurfaceSurfaceExtremum* out, SurfacePairEval* at_solution);

}  // namespace tangent::contact
