#pragma once

// The rows of a split contact (docs/contact.md, "Rows that stay on their minimum"): past a
// pitchfork of the distance a pair has a saddle with a minimum either side, each held by a row
// (SurfaceContactTerm::State::keep_off_saddles). These take a row whose evaluation ended on the
// saddle, or on the other minimum, back to its own. Allocation free.

#include <Eigen/Core>

#include "contact/extremal.h"
#include "contact/placed.h"
#include "contact/relative_curvature.h"
#include "nurbs/surface.h"

namespace tangent::optimizer::internal {

/// The minimum beside `saddle` (its evaluation `at`, relative curvature `rc`) on the side of
/// `toward` (periodic directions the short way round): f's point walked along the crossing
/// direction in steps growing from 1 % of the curvature radius while its distance to g falls,
/// then Newton from the lowest point, which must converge to a facing minimum lower than the
/// saddle. @return whether one was found (*out, *out_eval).
bool MinimumToward(const nurbs::NurbsSurface& f, const contact::BodyPose& pf,
                   const nurbs::NurbsSurface& g, const contact::BodyPose& pg,
                   const contact::SurfaceSurfaceExtremum& saddle,
                   const contact::SurfacePairEval& at, const contact::RelativeCurvature& rc,
                   const Eigen::Vector4d& toward, contact::SurfaceSurfaceExtremum* out,
                   contact::SurfacePairEval* out_eval);

/// The minimum on `from`'s side when `across`, a minimum an evaluation converged to, lies
/// across a saddle from `from` (the row's own side): higher than the distance over `from`, or
/// with a hump of that distance between them. @return whether one was found (*out, *out_eval);
/// false too when nothing shows a crossing.
bool MinimumOnOwnSide(const nurbs::NurbsSurface& f, const contact::BodyPose& pf,
                      const nurbs::NurbsSurface& g, const contact::BodyPose& pg,
                      const contact::SurfaceSurfaceExtremum& across, const Eigen::Vector4d& from,
                      contact::SurfaceSurfaceExtremum* out, contact::SurfacePairEval* out_eval);

}  // namespace tangent::optimizer::internal
