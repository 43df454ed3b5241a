#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbs/tessellation.h"

namespace tangent::nurbs {

/// A surface's certified tessellation moved out along the surface normals by `offset`: the
/// polygonal stand-in the global contact stage collides (seed 001 §5, design.md §2). Vertex k is
/// S(u_k, v_k) + r n(u_k, v_k) with the exact unit normal (at a degenerate point, such as a
/// sphere's pole, its limit from inside the domain), and keeps its parameters, so a
/// point of an offset triangle maps back to surface parameters by barycentric interpolation.
///
/// Margin argument (docs/contact.md, "Global stage"): with r = ε + margin, ε the tessellation's
/// certified bound, and H the offset mesh's distance from the true offset surface S + r n
/// (certified per mesh by CertifyOffsetMesh), two surfaces closer than 2(r − H) have offset
/// volumes that overlap, so their closed offset meshes intersect unless one contains the other.
struct OffsetMesh {
  TriangleMesh base;                      ///< the tessellation (vertices on S, parameters)
  std::vector<Eigen::Vector3d> vertices;  ///< offset vertices, surface frame
  double offset = 0.0;                    ///< r (m)
  double tessellation_bound = 0.0;        ///< ε (m)
};

/// @param tolerance the tessellation's target bound ε (m) @param margin (m) the distance below
/// which surfaces must be found; r = ε + margin. @param max_edge (m) when positive, no grid
/// cell's chord is longer (see Tessellate). @throws std::invalid_argument on non-positive
/// tolerance or margin.
OffsetMesh MakeOffsetMesh(const NurbsSurface& surface, double tolerance, double margin,
                          double max_edge = 0.0);

/// What CGAL says about an offset mesh when a scene loads.
struct OffsetCertificate {
  int triangles = 0;
  int self_intersecting_pairs = 0;  ///< pairs of triangles that intersect (CGAL, exact predicates)
  double min_curvature_radius = 0.0;  ///< smallest principal radius of curvature sampled (m)
  /// Smallest radius of curvature bending towards the offset side (concave, seen from the
  /// offset), m; infinite when none was sampled.
  double min_concave_radius = 0.0;
  bool offset_exceeds_curvature = false;  ///< r > min_concave_radius: the offset may fold
  /// One-sided Hausdorff bound: the largest distance from dense samples of the true offset
  /// surface S + r n to the mesh, m; each sample's distance taken to the triangles of the grid
  /// cell that holds its parameters, which is at least its distance to the mesh.
  double hausdorff = 0.0;
  int samples = 0;
  /// One line for the load log.
  std::string Report(const std::string& name) const;
};

/// Certifies `mesh` against its surface: self-intersection test, curvature radii and the
/// Hausdorff bound from `samples_per_direction`² surface samples.
OffsetCertificate CertifyOffsetMesh(const NurbsSurface& surface, const OffsetMesh& mesh,
                                    int samples_per_direction = 200);

}  // namespace tangent::nurbs
