#pragma once

// The minima the global stage adds beside its clusters' own (internal header, contact/global.cc):
// either side of a saddle of the distance (a split contact), and between nested surfaces, whose
// offsets contain one another without crossing (a ball in a socket). docs/contact.md, "Global
// stage".

#include <algorithm>
#include <vector>

#include "contact/extremal.h"
#include "contact/global.h"
#include "contact/relative_curvature.h"

namespace tangent::contact::internal {

/// Two contacts on the same points (m): far below any two distinct extrema a pass tells apart,
/// far above the solves' rounding (1e-15 of a part's size) and the servo's tracking error
/// (~1e-10 m).
inline constexpr double kSamePoint = 1e-8;

bool SamePoints(const GlobalContact& x, const GlobalContact& y);

/// Whether e, a singular extremum (ExtremalStatus::kSingular; `at` the pair's evaluation there),
/// is a continuum the servo holds as a line (GlobalOptions::accept_continuum): its relative
/// curvature line-like, λ_min < continuum_ratio · λ_max with λ_max > 0. Singular elsewhere (a
/// ball on a hole's rim, where the wall's border meets the plate's trim edge; a pole) it is no
/// line, and held as a point it is lost again every tick (docs/contact.md, "Line contacts").
inline bool LineContinuum(const GlobalOptions& options, const SurfaceSurfaceExtremum& e,
                          const SurfacePairEval& at) {
  if (!options.accept_continuum || e.status != ExtremalStatus::kSingular) return false;
  const RelativeCurvature rc = RelativeCurvatureOf(at);
  return rc.valid && rc.eigenvalues[1] > 0.0 &&
         rc.eigenvalues[0] < options.continuum_ratio * rc.eigenvalues[1];
}

/// Appends c to *out unless a contact on the same points is there.
void AddFound(const GlobalContact& c, std::vector<GlobalContact>* out);

/// The minima beside a saddle of the distance (relative_curvature.h): the surfaces cross along
/// the eigenvector w of M's negative eigenvalue, so a minimum (the deepest point of the crossing,
/// or the nearest of a near miss) lies on each side of the saddle along w. Newton from a seed
/// beside the saddle is drawn back to it (the nearest critical point), so each side first walks
/// f's point along w, in steps growing from 1 % of the curvature radius 1/max|λ|, while its
/// signed distance to g (a point–surface solve) keeps falling; Newton from the lowest point
/// then lands in the minimum's basin. A result that converges to a minimum (not itself crossing)
/// on that side, facing and within the activation and penetration bounds, is appended to *out
/// unless already there.
void MinimaBeside(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                  const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                  const SurfaceSurfaceExtremum& saddle, const SurfacePairEval& at,
                  const RelativeCurvature& rc, const GlobalOptions& options, int a, int b,
                  std::vector<GlobalContact>* out);

/// A world box (axis aligned) and whether it holds another whole.
struct WorldBox {
  Eigen::Vector3d lo, hi;
  bool Overlaps(const WorldBox& o) const {
    return (lo.array() <= o.hi.array()).all() && (o.lo.array() <= hi.array()).all();
  }
  double Volume() const { return (hi - lo).cwiseMax(0.0).prod(); }
  /// Whether at least half of the smaller of the two boxes lies in the other: where two
  /// surfaces may nest (a ball in a socket, a rod along a groove).
  bool MostlyShares(const WorldBox& o) const {
    const WorldBox common{lo.cwiseMax(o.lo), hi.cwiseMin(o.hi)};
    return common.Volume() >= 0.5 * std::min(Volume(), o.Volume());
  }
};

/// The minimum of a nested pair: surfaces whose offset meshes' boxes mostly share their space
/// (WorldBox::MostlyShares) and whose offsets no triangle of the narrow phase found crossing.
/// Offsets that contain one another never cross (a ball in a socket of nearly its radius: the
/// socket's offset shell lies inside the ball's; a rod along a groove), so the margin argument
/// finds nothing, however near the surfaces are. Solved cold from the closest of 5 × 5 samples of
/// each (ClosestSamplePair) with the neighbourhood search; appended to *out when it converges,
/// facing, within the activation and penetration bounds and not at a saddle (the minima beside a
/// saddle are appended instead). For untrimmed surfaces (a trimmed face's nesting is its solid's
/// other faces').
void NestedPairMinimum(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                       const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                       const GlobalOptions& options, int a, int b, std::vector<GlobalContact>* out);

}  // namespace tangent::contact::internal
