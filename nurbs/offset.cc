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
  out.vertices.resize(n);
  for (size_t k = 0; k < n; ++k) {
    // At a degenerate point (a sphere's pole) the limit of the normals from inside the domain.
    const double u = out.base.uv[k][0], v = out.base.uv[k][1];
    const Eigen::Vector3d normal = UnitNormal(surface, u, v, surface.Evaluate(u, v, 2));
    out.vertices[k] = out.base.vertices[k] + out.offset * normal;
  }
  return out;
}

}  // namespace tangent::nurbs
