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
#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

/// A placed surface sampled on an (n+1)² even grid over its domain, edges and corners included.
struct Grid {
  int n = 0;
  Eigen::Vector2d lo, hi;
  std::vector<Eigen::Vector3d> x;  ///< world points, index i·(n+1) + j (u step i, v step j)
  Eigen::Vector2d Uv(int i, int j) const {
    return {lo[0] + (hi[0] - lo[0]) * i / n, lo[1] + (hi[1] - lo[1]) * j / n};
  }
  const Eigen::Vector3d& At(int i, int j) const { return x[static_cast<size_t>(i * (n + 1) + j)]; }
};

Grid Sample(const nurbs::NurbsSurface& s, const BodyPose& pose, int n) {
  Grid g;
  g.n = n;
  g.lo = {s.knots_u().domain_begin(), s.knots_v().domain_begin()};
  g.hi = {s.knots_u().domain_end(), s.knots_v().domain_end()};
  g.x.reserve(static_cast<size_t>((n + 1) * (n + 1)));
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const Eigen::Vector2d uv = g.Uv(i, j);
      g.x.push_back(pose.Point(s.Evaluate(uv[0], uv[1], 0).S));
    }
  }
  return g;
}

/// The sample of `grid` closest to x: its (i, j) and squared distance.
double ClosestTo(const Grid& grid, const Eigen::Vector3d& x, int* bi, int* bj) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= grid.n; ++i) {
    for (int j = 0; j <= grid.n; ++j) {
      const double d = (grid.At(i, j) - x).squaredNorm();
      if (d < best) {
        best = d;
        *bi = i;
        *bj = j;
      }
    }
  }
  return best;
}

/// One side of a domain: the edge v = lo/hi (along u) or u = lo/hi (along v), as a straight
/// domain curve τ ∈ [0, 1] and the grid samples on it.
struct Edge {
  bool along_u;  ///< the edge runs along u (v held)
  bool high;     ///< held at the domain's upper end
};
constexpr std::array<Edge, 4> kEdges = {
    {{true, false}, {true, true}, {false, false}, {false, true}}};

bool IsBoundary(const nurbs::NurbsSurface& s, const Edge& e) {
  // A periodic direction's ends are its seam, not a boundary: the edges held in it are none.
  return e.along_u ? !s.periodic_v() : !s.periodic_u();
}

/// (i, j) of sample k ∈ [0, n] along edge e.
void EdgeSample(const Grid& g, const Edge& e, int k, int* i, int* j) {
  *i = e.along_u ? k : (e.high ? g.n : 0);
  *j = e.along_u ? (e.high ? g.n : 0) : k;
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
void SearchEdges(const nurbs::NurbsSurface& a, const BodyPose& pose_a, const Grid& ga,
                 const nurbs::NurbsSurface& b, const BodyPose& pose_b, const Grid& gb, bool a_is_f,
                 Candidate* best) {
  for (const Edge& e : kEdges) {
    if (!IsBoundary(a, e)) continue;
    double nearest = std::numeric_limits<double>::infinity();
    int ek = 0, bi = 0, bj = 0;
    for (int k = 0; k <= ga.n; ++k) {
      int i = 0, j = 0, si = 0, sj = 0;
      EdgeSample(ga, e, k, &i, &j);
      const double d = ClosestTo(gb, ga.At(i, j), &si, &sj);
      if (d < nearest) {
        nearest = d;
        ek = k;
        bi = si;
        bj = sj;
      }
    }
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    EdgeSample(ga, e, 0, &i0, &j0);
    EdgeSample(ga, e, ga.n, &i1, &j1);
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
void SearchCorners(const nurbs::NurbsSurface& a, const Grid& ga, const nurbs::NurbsSurface& b,
                   const BodyPose& pose_b, const Grid& gb, bool a_is_f, Candidate* best) {
  if (a.periodic_u() || a.periodic_v()) return;  // (its corners lie on a seam)
  for (int ci = 0; ci < 2; ++ci) {
    for (int cj = 0; cj < 2; ++cj) {
      const int i = ci * ga.n, j = cj * ga.n;
      int si = 0, sj = 0;
      ClosestTo(gb, ga.At(i, j), &si, &sj);
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
  const Grid a = Sample(f, pose_f, n), b = Sample(g, pose_g, n);
  double nearest = std::numeric_limits<double>::infinity();
  Eigen::Vector4d seed = Eigen::Vector4d::Zero();
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      int si = 0, sj = 0;
      const double d = ClosestTo(b, a.At(i, j), &si, &sj);
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
