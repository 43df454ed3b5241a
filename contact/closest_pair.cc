// The closest-sample seed of a surface pair, with the domains' edges and corners searched as
// problems of their own (issue 38): a boundary minimum is a minimum of a lower-dimensional
// problem, curve–surface along an edge and point–surface at a corner, and its basin in the
// four-parameter problem can be too thin for the closest sample of a grid to start in it.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "contact/extremal.h"
#include "contact/sample_grid.h"
#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

using internal::ClosestSample;
using internal::EdgeAlongU;
using internal::EdgeSample;

/// A placed surface sampled on an (n+1)² even grid over its domain, edges and corners included
/// (the points held here, the grid a view of them).
struct Grid {
  std::vector<Eigen::Vector3d> points;
  internal::SampleGrid g;
};

Grid Sample(const nurbs::NurbsSurface& s, const BodyPose& pose, int n) {
  Grid out;
  out.points.resize(static_cast<size_t>((n + 1) * (n + 1)));
  out.g = {n,
           {s.knots_u().domain_begin(), s.knots_v().domain_begin()},
           {s.knots_u().domain_end(), s.knots_v().domain_end()},
           out.points.data()};
  out.g.Sample(s, pose);
  return out;
}

/// A domain edge (SampleGrid's numbering) that is a boundary: a periodic direction's ends are
/// its seam, and the edges held in it are none.
bool IsBoundary(const nurbs::NurbsSurface& s, int edge) {
  return EdgeAlongU(edge) ? !s.periodic_v() : !s.periodic_u();
}

/// A candidate: the pair's parameters and the distance between its points.
struct Candidate {
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  double distance = std::numeric_limits<double>::infinity();
};

bool IsMinimum(ExtremalStatus s, ExtremumKind k) {
  return (s == ExtremalStatus::kConverged || s == ExtremalStatus::kAtBoundary) &&
         k == ExtremumKind::kMinimum;
}

/// The minima of the edges of `a` (the pair's first surface when `a_is_f`) against surface b,
/// each from its own closest sample pair, solved as curve–surface problems; the best into *best.
void SearchEdges(const nurbs::NurbsSurface& a, const BodyPose& pose_a,
                 const internal::SampleGrid& ga, const nurbs::NurbsSurface& b,
                 const BodyPose& pose_b, const internal::SampleGrid& gb, bool a_is_f,
                 Candidate* best) {
  for (int e = 0; e < 4; ++e) {
    if (!IsBoundary(a, e)) continue;
    double nearest = std::numeric_limits<double>::infinity();
    int ek = 0, bi = 0, bj = 0;
    for (int k = 0; k <= ga.n; ++k) {
      int i = 0, j = 0, si = 0, sj = 0;
      EdgeSample(ga.n, e, k, &i, &j);
      const double d = ClosestSample(gb, ga.At(i, j), &si, &sj);
      if (d < nearest) {
        nearest = d;
        ek = k;
        bi = si;
        bj = sj;
      }
    }
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    EdgeSample(ga.n, e, 0, &i0, &j0);
    EdgeSample(ga.n, e, ga.n, &i1, &j1);
    const Eigen::Vector2d from = ga.Uv(i0, j0), to = ga.Uv(i1, j1);
    const nurbs::NurbsCurve2d line = nurbs::MakePolyline2d({from, to});  // τ ∈ [0, 1]
    const BodyCurve curve(&a, &line);
    const CurveSurfaceExtremum c = SolveCurveSurface(
        b, pose_b, curve, pose_a,
        Eigen::Vector3d(gb.Uv(bi, bj)[0], gb.Uv(bi, bj)[1], static_cast<double>(ek) / ga.n));
    if (!IsMinimum(c.status, c.kind)) continue;
    const double distance = (c.p_g - c.p_f).norm();
    if (distance >= best->distance) continue;
    const Eigen::Vector2d on_a = from + c.u[2] * (to - from);
    best->distance = distance;
    best->u = a_is_f ? Eigen::Vector4d(on_a[0], on_a[1], c.u[0], c.u[1])
                     : Eigen::Vector4d(c.u[0], c.u[1], on_a[0], on_a[1]);
  }
}

/// The minima of the corners of `a` against surface b, as point–surface problems.
void SearchCorners(const nurbs::NurbsSurface& a, const internal::SampleGrid& ga,
                   const nurbs::NurbsSurface& b, const BodyPose& pose_b,
                   const internal::SampleGrid& gb, bool a_is_f, Candidate* best) {
  if (a.periodic_u() || a.periodic_v()) return;  // (its corners lie on a seam)
  for (int ci = 0; ci < 2; ++ci) {
    for (int cj = 0; cj < 2; ++cj) {
      const int i = ci * ga.n, j = cj * ga.n;
      int si = 0, sj = 0;
      ClosestSample(gb, ga.At(i, j), &si, &sj);
      const PointSurfaceExtremum p = SolvePointSurface(ga.At(i, j), b, pose_b, gb.Uv(si, sj));
      if (!IsMinimum(p.status, p.kind)) continue;
      const double distance = (ga.At(i, j) - p.p_f).norm();
      if (distance >= best->distance) continue;
      const Eigen::Vector2d corner = ga.Uv(i, j);
      best->distance = distance;
      best->u = a_is_f ? Eigen::Vector4d(corner[0], corner[1], p.u[0], p.u[1])
                       : Eigen::Vector4d(p.u[0], p.u[1], corner[0], corner[1]);
    }
  }
}

}  // namespace

Eigen::Vector4d ClosestSamplePair(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const BodyPose& pose_g, int n,
                                  double* distance) {
  const Grid sa = Sample(f, pose_f, n), sb = Sample(g, pose_g, n);
  const internal::SampleGrid& a = sa.g;
  const internal::SampleGrid& b = sb.g;
  double nearest = std::numeric_limits<double>::infinity();
  Eigen::Vector4d seed = Eigen::Vector4d::Zero();
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      int si = 0, sj = 0;
      const double d = ClosestSample(b, a.At(i, j), &si, &sj);
      if (d < nearest) {
        nearest = d;
        seed << a.Uv(i, j), b.Uv(si, sj);
      }
    }
  }
  if (distance) *distance = std::sqrt(nearest);
  if (!std::isfinite(nearest)) return seed;
  // The four-parameter solve from the closest sample. When it ends apart, the edges and the
  // corners are searched as curve–surface and point–surface problems, and a minimum of theirs
  // nearer than the solve's answer is the seed instead (the solver, seeded at a boundary
  // minimum, stays there: BoundaryMinimaTest). A touching or interpenetrating pair keeps the
  // closest sample: its extremum is the penetration's, which no boundary problem measures.
  const SurfaceSurfaceExtremum interior = SolveSurfaceSurface(f, pose_f, g, pose_g, seed);
  if (!(interior.beta > 0.0)) return seed;
  const double solved = (interior.p_f - interior.p_g).norm();
  Candidate best;
  best.distance = solved;
  SearchEdges(f, pose_f, a, g, pose_g, b, /*a_is_f=*/true, &best);
  SearchEdges(g, pose_g, b, f, pose_f, a, /*a_is_f=*/false, &best);
  SearchCorners(f, a, g, pose_g, b, /*a_is_f=*/true, &best);
  SearchCorners(g, b, f, pose_f, a, /*a_is_f=*/false, &best);
  // Only a clearly nearer boundary minimum replaces the seed (not the same one found again).
  const double margin = 1e-12 * std::max(1.0, solved);
  return best.distance < solved - margin ? best.u : seed;
}

}  // namespace tangent::contact
