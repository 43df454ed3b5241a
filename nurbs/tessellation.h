#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "nurbs/surface.h"

namespace tangent::nurbs {

/// A triangle mesh of a surface. Vertices lie on the surface and carry their parameters.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;      ///< S(u, v), surface frame, metres
  std::vector<Eigen::Vector2d> uv;            ///< (u, v) of each vertex
  std::vector<std::array<int, 3>> triangles;  ///< vertex indices, counter-clockwise in (u, v)
  std::vector<double> u_lines, v_lines;       ///< the parameter grid the mesh is built on
  /// The grid cell of each triangle (cell i·(v_lines − 1) + j spans u_lines[i..i+1] and
  /// v_lines[j..j+1]); empty for a full grid, where triangle t lies in cell t / 2.
  std::vector<int> cells;
  int CellOf(int t) const { return cells.empty() ? t / 2 : cells[static_cast<size_t>(t)]; }
  /// Certified bound: every surface point S(u, v) is within this distance of the mesh; more
  /// precisely, of one of the two triangles of the grid cell that contains (u, v).
  double error_bound = 0.0;
};

/// Tessellates a surface on a tensor grid of parameter lines (so the mesh is watertight, with no
/// T-junctions), refined by halving grid intervals until every cell's certified bound is at
/// most `tolerance` or the grid reaches `max_lines` lines in a direction (then the bound
/// reported is larger than the tolerance, never wrong).
///
/// The bound of a cell comes from its own Bezier net, found by the Oslo algorithm (blossoms at
/// the cell's corner parameters). With positive weights, S(u,v) is a convex combination
/// Σ λ_ab P_ab of the net's Cartesian points; with (ū, v̄) = Σ λ_ab (a/p, b/q) in the cell,
///   |S − M(ū,v̄)| ≤ max_ab |P_ab − L(a/p, b/q)| + |d|/4 + |d|/4,
/// where L is the bilinear interpolant of the four corners (which lie on the surface), M the
/// two-triangle split of the cell along its (0,0)–(1,1) diagonal, and d = P00 − P10 − P01 + P11
/// the twist: the first |d|/4 bounds Σλ L(x) − L(Σλx) = d·Cov(a/p, b/q), the second |L − M|.
///
/// With `max_edge` > 0, an interval is also halved while a cell's chord along it (between its
/// corners) is longer than max_edge: flat stretches (a wire's straight legs) then get cells of
/// bounded size, which the global contact stage needs to tell contacts apart along a surface.
/// @throws std::invalid_argument when tolerance is not positive or max_edge is negative.
TriangleMesh Tessellate(const NurbsSurface& surface, double tolerance, int max_lines = 4097,
                        double max_edge = 0.0);

/// Distance from x to the two triangles of the grid cell of `mesh` that contains (u, v)
/// (clamped to the grid). For x = S(u, v) this is at most `mesh.error_bound`.
double DistanceToCell(const TriangleMesh& mesh, double u, double v, const Eigen::Vector3d& x);

/// Distance from point x to triangle (a, b, c) (closest point by Voronoi regions).
double PointTriangleDistance(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace tangent::nurbs
