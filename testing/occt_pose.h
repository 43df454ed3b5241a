#pragma once

// Open CASCADE copies of our surfaces placed in the world by a body pose (for peer benchmarks
// and cross-checks only).

#include <Geom_BSplineSurface.hxx>
#include <gp_Quaternion.hxx>
#include <gp_Trsf.hxx>

#include "contact/placed.h"
#include "testing/occt_convert.h"

namespace tangent::contact::testing {

inline Handle(Geom_BSplineSurface) ToOcctPlaced(const nurbs::NurbsSurface& s, const Vector7d& q) {
  Handle(Geom_BSplineSurface) o = nurbs::testing::ToOcct(s);
  gp_Trsf t;
  const Eigen::Vector4d Q = q.tail<4>().normalized();
  t.SetTransformation(gp_Quaternion(Q[1], Q[2], Q[3], Q[0]), gp_Vec(q[0], q[1], q[2]));
  o->Transform(t);
  return o;
}

}  // namespace tangent::contact::testing
