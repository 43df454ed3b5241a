#pragma once

// Conversion of our NURBS to Open CASCADE's, for cross-checks and peer benchmarks only.
// Open CASCADE stores distinct knots with multiplicities and Cartesian poles with weights.

#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array2OfPnt.hxx>

#include "nurbs/curve.h"
#include "nurbs/surface.h"

namespace tangent::nurbs::testing {

inline void KnotsAndMults(const KnotVector& k, TColStd_Array1OfReal* knots,
                          TColStd_Array1OfInteger* mults) {
  std::vector<double> distinct;
  std::vector<int> m;
  for (double t : k.knots()) {
    if (distinct.empty() || t != distinct.back()) {
      distinct.push_back(t);
      m.push_back(1);
    } else {
      ++m.back();
    }
  }
  knots->Resize(1, static_cast<int>(distinct.size()), false);
  mults->Resize(1, static_cast<int>(distinct.size()), false);
  for (size_t i = 0; i < distinct.size(); ++i) {
    knots->SetValue(static_cast<int>(i) + 1, distinct[i]);
    mults->SetValue(static_cast<int>(i) + 1, m[i]);
  }
}

inline Handle(Geom_BSplineSurface) ToOcct(const NurbsSurface& s) {
  TColgp_Array2OfPnt poles(1, s.num_u(), 1, s.num_v());
  TColStd_Array2OfReal weights(1, s.num_u(), 1, s.num_v());
  for (int i = 0; i < s.num_u(); ++i) {
    for (int j = 0; j < s.num_v(); ++j) {
      const Eigen::Vector3d p = s.point(i, j);
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
      weights.SetValue(i + 1, j + 1, s.weight(i, j));
    }
  }
  TColStd_Array1OfReal uk(1, 1), vk(1, 1);
  TColStd_Array1OfInteger um(1, 1), vm(1, 1);
  KnotsAndMults(s.knots_u(), &uk, &um);
  KnotsAndMults(s.knots_v(), &vk, &vm);
  if (!s.IsRational()) {
    return new Geom_BSplineSurface(poles, uk, vk, um, vm, s.degree_u(), s.degree_v());
  }
  return new Geom_BSplineSurface(poles, weights, uk, vk, um, vm, s.degree_u(), s.degree_v());
}

inline Handle(Geom_BSplineCurve) ToOcct(const NurbsCurve<3>& c) {
  TColgp_Array1OfPnt poles(1, c.num_points());
  TColStd_Array1OfReal weights(1, c.num_points());
  for (int i = 0; i < c.num_points(); ++i) {
    const Eigen::Vector3d p = c.point(i);
    poles.SetValue(i + 1, gp_Pnt(p.x(), p.y(), p.z()));
    weights.SetValue(i + 1, c.weight(i));
  }
  TColStd_Array1OfReal k(1, 1);
  TColStd_Array1OfInteger m(1, 1);
  KnotsAndMults(c.knots(), &k, &m);
  return new Geom_BSplineCurve(poles, weights, k, m, c.degree());
}

inline Eigen::Vector3d ToEigen(const gp_XYZ& x) { return {x.X(), x.Y(), x.Z()}; }

}  // namespace tangent::nurbs::testing
