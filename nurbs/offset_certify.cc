// CGAL certification of offset meshes (design.md: CGAL 5.5 for mesh certification). Kept in its
// own translation unit: CGAL's headers are heavy and nothing else in the library needs them.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <algorithm>
#include <array>
#include <limits>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <tuple>

#include "nurbs/offset.h"

namespace tangent::nurbs {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

// The offset mesh as a CGAL surface mesh with coincident vertices welded (a closed surface's
// seam and a sphere's poles repeat vertices in the parameter grid; unwelded, the faces on the
// two sides of a seam would count as intersecting along it). Triangles that collapse are dropped.
// Only the vertices of the mesh's triangles are taken (a mesh cut along a trim keeps the whole
// grid's vertices).
Mesh Welded(const OffsetMesh& m) {
  std::vector<char> used(m.vertices.size(), 0);
  for (const auto& t : m.base.triangles) {
    for (int k : t) used[static_cast<size_t>(k)] = 1;
  }
  double scale = 1.0;
  for (size_t k = 0; k < m.vertices.size(); ++k) {
    if (used[k]) scale = std::max(scale, m.vertices[k].cwiseAbs().maxCoeff());
  }
  const double q = 1e-12 * scale;
  std::map<std::tuple<long long, long long, long long>, Mesh::Vertex_index> index;
  std::vector<Mesh::Vertex_index> map(m.vertices.size());
  Mesh mesh;
  for (size_t k = 0; k < m.vertices.size(); ++k) {
    if (!used[k]) continue;
    const Eigen::Vector3d& v = m.vertices[k];
    const auto key =
        std::make_tuple(std::llround(v.x() / q), std::llround(v.y() / q), std::llround(v.z() / q));
    const auto it = index.find(key);
    if (it != index.end()) {
      map[k] = it->second;
    } else {
      map[k] = mesh.add_vertex(Point(v.x(), v.y(), v.z()));
      index.emplace(key, map[k]);
    }
  }
  for (const auto& t : m.base.triangles) {
    const auto a = map[static_cast<size_t>(t[0])], b = map[static_cast<size_t>(t[1])],
               c = map[static_cast<size_t>(t[2])];
    if (a == b || b == c || a == c) continue;
    mesh.add_face(a, b, c);  // (a non-manifold face is skipped; none arise from a grid)
  }
  return mesh;
}

}  // namespace

OffsetCertificate CertifyOffsetMesh(const NurbsSurface& surface, const OffsetMesh& m,
                                    int samples_per_direction) {
  OffsetCertificate c;
  const Mesh mesh = Welded(m);
  c.triangles = static_cast<int>(mesh.number_of_faces());
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(faces(mesh), mesh, std::back_inserter(pairs));
  c.self_intersecting_pairs = static_cast<int>(pairs.size());

  const double u0 = surface.knots_u().domain_begin(), u1 = surface.knots_u().domain_end();
  const double v0 = surface.knots_v().domain_begin(), v1 = surface.knots_v().domain_end();
  const int n = std::max(2, samples_per_direction);
  double min_radius = std::numeric_limits<double>::infinity();
  double min_concave = std::numeric_limits<double>::infinity();
  double worst = 0.0;
  // A mesh cut along a trim (CutAlongTrim) covers only its kept cells: sample those.
  const std::vector<double>& ul = m.base.u_lines;
  const std::vector<double>& vl = m.base.v_lines;
  const size_t nv = vl.size() > 1 ? vl.size() - 1 : 1;
  // The triangles of each grid cell (at most two; -1: none, the cell was cut away).
  std::vector<std::array<int, 2>> of_cell(nv * (ul.size() > 1 ? ul.size() - 1 : 1), {-1, -1});
  for (int t = 0; t < static_cast<int>(m.base.triangles.size()); ++t) {
    std::array<int, 2>& slot = of_cell[static_cast<size_t>(m.base.CellOf(t))];
    (slot[0] < 0 ? slot[0] : slot[1]) = t;
  }
  auto cell_of = [&](double u, double v) -> const std::array<int, 2>& {
    const auto cu = std::upper_bound(ul.begin() + 1, ul.end() - 1, u) - ul.begin() - 1;
    const auto cv = std::upper_bound(vl.begin() + 1, vl.end() - 1, v) - vl.begin() - 1;
    return of_cell[static_cast<size_t>(cu) * nv + static_cast<size_t>(cv)];
  };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = u0 + (u1 - u0) * (i + 0.5) / n, v = v0 + (v1 - v0) * (j + 0.5) / n;
      const std::array<int, 2>& cell = cell_of(u, v);
      if (cell[0] < 0) continue;
      const SurfacePoint p = surface.Evaluate(u, v, 2);
      const Eigen::Vector3d N = p.S_u.cross(p.S_v);
      if (!(N.norm() > 0.0)) continue;
      const Eigen::Vector3d nrm = N.normalized();
      const Eigen::Vector3d x = p.S + m.offset * nrm;
      // The distance to the cell's own triangles: at least the distance to the mesh, so the
      // largest is still an upper bound of the one-sided Hausdorff distance.
      double d = std::numeric_limits<double>::infinity();
      for (int t : cell) {
        if (t < 0) continue;
        const auto& tri = m.base.triangles[static_cast<size_t>(t)];
        d = std::min(d, PointTriangleDistance(x, m.vertices[static_cast<size_t>(tri[0])],
                                              m.vertices[static_cast<size_t>(tri[1])],
                                              m.vertices[static_cast<size_t>(tri[2])]));
      }
      worst = std::max(worst, d);
      ++c.samples;
      // Principal curvatures: eigenvalues of I⁻¹ II (II with the outward normal): κ > 0 where
      // the surface bends towards the offset side, which folds an offset larger than 1/κ.
      Eigen::Matrix2d I, II;
      I << p.S_u.dot(p.S_u), p.S_u.dot(p.S_v), p.S_u.dot(p.S_v), p.S_v.dot(p.S_v);
      II << p.S_uu.dot(nrm), p.S_uv.dot(nrm), p.S_uv.dot(nrm), p.S_vv.dot(nrm);
      const Eigen::Vector2cd kappa = (I.inverse() * II).eigenvalues();
      for (int e = 0; e < 2; ++e) {
        const double k = kappa[e].real();
        if (std::abs(k) > 0.0) min_radius = std::min(min_radius, 1.0 / std::abs(k));
        if (k > 0.0) min_concave = std::min(min_concave, 1.0 / k);
      }
    }
  }
  c.hausdorff = worst;
  c.min_curvature_radius = min_radius;
  c.min_concave_radius = min_concave;
  c.offset_exceeds_curvature = m.offset > min_concave;
  return c;
}

std::string OffsetCertificate::Report(const std::string& name) const {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "offset mesh %s: %d triangles, %d self-intersecting pairs, Hausdorff %.3g m over "
                "%d samples, smallest curvature radius %.3g m%s",
                name.c_str(), triangles, self_intersecting_pairs, hausdorff, samples,
                min_curvature_radius,
                offset_exceeds_curvature ? " — WARNING: the offset exceeds a concave radius of "
                                           "curvature (the offset folds)"
                                         : "");
  return buf;
}

}  // namespace tangent::nurbs
