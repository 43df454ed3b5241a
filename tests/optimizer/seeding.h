#pragma once

// Seeds for contact terms in tests: the nearest pair of samples of two placed surfaces.

#include <vector>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::optimizer::testing {

/// (u, v, s, t) of the nearest pair among n x n samples of each surface (cell centres).
inline Eigen::Vector4d NearestSamplePair(const nurbs::NurbsSurface& f, const contact::BodyPose& pf,
                                         const nurbs::NurbsSurface& g, const contact::BodyPose& pg,
                                         int n = 24) {
  auto samples = [n](const nurbs::NurbsSurface& s, const contact::BodyPose& p,
                     std::vector<Eigen::Vector3d>* pts, std::vector<Eigen::Vector2d>* uv) {
    const double u0 = s.knots_u().domain_begin(), u1 = s.knots_u().domain_end();
    const double v0 = s.knots_v().domain_begin(), v1 = s.knots_v().domain_end();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector2d x(u0 + (u1 - u0) * (i + 0.5) / n, v0 + (v1 - v0) * (j + 0.5) / n);
        uv->push_back(x);
        pts->push_back(p.Point(s.Evaluate(x[0], x[1], 0).S));
      }
    }
  };
  std::vector<Eigen::Vector3d> a, b;
  std::vector<Eigen::Vector2d> ua, ub;
  samples(f, pf, &a, &ua);
  samples(g, pg, &b, &ub);
  double best = 1e300;
  Eigen::Vector4d seed = Eigen::Vector4d::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i] - b[j]).squaredNorm();
      if (d < best) {
        best = d;
        seed << ua[i], ub[j];
      }
    }
  }
  return seed;
}

}  // namespace tangent::optimizer::testing
