#include "contact/face_gap.h"

#include "contact/extremal.h"

namespace tangent::contact {

FaceCorner LowestCorner(const nurbs::NurbsSurface& f, const nurbs::FlatQuad& qf, const BodyPose& pf,
                        const nurbs::NurbsSurface& g, const nurbs::FlatQuad& qg,
                        const BodyPose& pg) {
  FaceCorner best;
  for (int side = 0; side < 2; ++side) {
    const bool of_f = side == 0;
    const nurbs::FlatQuad& q = of_f ? qf : qg;
    const BodyPose& p = of_f ? pf : pg;
    const nurbs::NurbsSurface& other = of_f ? g : f;
    const nurbs::FlatQuad& other_q = of_f ? qg : qf;
    const BodyPose& po = of_f ? pg : pf;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d x = p.Point(q.points[static_cast<size_t>(k)]);
      const PointSurfaceExtremum e = SolvePointSurface(x, other, po, other_q.middle);
      if (e.status != ExtremalStatus::kConverged) continue;  // not over the other face
      if (best.found && !(e.distance < best.beta)) continue;
      best.found = true;
      best.of_f = of_f;
      best.corner = k;
      best.beta = e.distance;
      const Eigen::Vector2d& c = q.corners[static_cast<size_t>(k)];
      best.u = of_f ? Eigen::Vector4d(c[0], c[1], e.u[0], e.u[1])
                    : Eigen::Vector4d(e.u[0], e.u[1], c[0], c[1]);
      best.p_f = of_f ? x : e.p_f;
      best.p_g = of_f ? e.p_f : x;
    }
  }
  return best;
}

}  // namespace tangent::contact
