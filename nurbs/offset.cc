#include "nurbs/offset.h"

#include <Eigen/Geometry>
#include <stdexcept>

namespace tangent::nurbs {

OffsetMesh MakeOffsetMesh(const NurbsSurface& surface, double tolerance, double margin,
                          double max_edge) {
  if (!(tolerance > 0.0)) throw std::invalid_argument("offset mesh: tolerance must be positive");
  if (!(margin > 0.0)) throw std::invalid_argument("offset mesh: margin must be positive");
  OffsetMesh out;
  out.base = Tessellate(surface, tolerance, 4097, max_edge);
  out.tessellation_bound = out.base.error_bound;
  out.offset = out.tessellation_bound + margin;
  const size_t n = out.base.vertices.size();
  double scale = 0.0;
  for (const Eigen::Vector3d& v : out.base.vertices) scale = std::max(scale, v.norm());
  out.vertices.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const SurfacePoint p = surface.Evaluate(out.base.uv[k][0], out.base.uv[k][1], 1);
    Eigen::Vector3d N = p.S_u.cross(p.S_v);
    // A degenerate point (a sphere's pole: S_u = 0): the normal is the limit of the normals next
    // to it; take it 1e-6 of the domain inward in both directions.
    for (double step = 1e-6; !(N.norm() > 1e-12 * (1.0 + scale * scale)) && step < 1e-2;
         step *= 10) {
      const double u0 = surface.knots_u().domain_begin(), u1 = surface.knots_u().domain_end();
      const double v0 = surface.knots_v().domain_begin(), v1 = surface.knots_v().domain_end();
      const double u =
          out.base.uv[k][0] + step * (u1 - u0) * (out.base.uv[k][0] < 0.5 * (u0 + u1) ? 1 : -1);
      const double v =
          out.base.uv[k][1] + step * (v1 - v0) * (out.base.uv[k][1] < 0.5 * (v0 + v1) ? 1 : -1);
      const SurfacePoint q = surface.Evaluate(u, v, 1);
      N = q.S_u.cross(q.S_v);
    }
    out.vertices[k] = out.base.vertices[k] + out.offset * N.normalized();
  }
  return out;
}

}  // namespace tangent::nurbs
