// TrimmedArea (nurbs/area.h) against areas known in closed form, and against a direct tensor
// quadrature over the whole domain of a curved patch.

#include "nurbs/area.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "nurbs/primitives.h"

namespace tangent::nurbs {
namespace {

TrimmedDomain Trim(std::optional<TrimLoop> outer, std::vector<TrimLoop> holes) {
  std::vector<std::string> warnings;
  return TrimmedDomain({0.0, 0.0}, {1.0, 1.0}, std::move(outer), std::move(holes), {}, &warnings);
}

TEST(AreaTest, APlaneWithACircularHole) {
  const NurbsSurface plane = MakePlanePatch({0, 0, 0}, {2, 0, 0}, {0, 3, 0});
  EXPECT_NEAR(TrimmedArea(plane), 6.0, 1e-13);
  const TrimmedDomain holed = Trim(std::nullopt, {TrimLoop{{MakeCircle2d({0.5, 0.4}, 0.2, true)}}});
  EXPECT_NEAR(TrimmedArea(plane, &holed) / (6.0 * (1.0 - 0.04 * M_PI)), 1.0, 1e-12);
}

TEST(AreaTest, ASphereAndItsNorthernHemisphere) {
  const double r = 2.0;
  const NurbsSurface sphere = MakeSphere({1, -1, 0.5}, r);
  EXPECT_NEAR(TrimmedArea(sphere) / (4.0 * M_PI * r * r), 1.0, 1e-12);
  // v = 1/2 is the equator (the profile is two quarter circles).
  const TrimmedDomain north =
      Trim(TrimLoop{{MakePolyline2d({{0, 0.5}, {1, 0.5}, {1, 1}, {0, 1}, {0, 0.5}})}}, {});
  EXPECT_NEAR(TrimmedArea(sphere, &north) / (2.0 * M_PI * r * r), 1.0, 1e-12);
}

TEST(AreaTest, ATorus) {
  const NurbsSurface torus = MakeTorus(3.0, 0.5);
  EXPECT_NEAR(TrimmedArea(torus) / (4.0 * M_PI * M_PI * 3.0 * 0.5), 1.0, 1e-12);
}

// A curved, sheared rational patch: the contour integral against a plain tensor Gauss quadrature
// of |S_u × S_v| over each knot span, very fine.
TEST(AreaTest, ACurvedPatchMatchesATensorQuadrature) {
  for (bool rational : {false, true}) {
    const NurbsSurface s = MakeShearedPatch(0.4, 1.5, 0.3, rational);
    const double u0 = s.knots_u().domain_begin(), u1 = s.knots_u().domain_end();
    const double v0 = s.knots_v().domain_begin(), v1 = s.knots_v().domain_end();
    // Composite midpoint-free Gauss: 5-point rule on a 64 × 64 grid.
    const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                         0.9061798459386640};
    const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                         0.4786286704993665, 0.2369268850561891};
    const int n = 64;
    double direct = 0.0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double hu = (u1 - u0) / n, hv = (v1 - v0) / n;
        for (int a = 0; a < 5; ++a) {
          for (int b = 0; b < 5; ++b) {
            const double u = u0 + hu * (i + 0.5 + 0.5 * x[a]), v = v0 + hv * (j + 0.5 + 0.5 * x[b]);
            const SurfacePoint p = s.Evaluate(u, v, 1);
            direct += 0.25 * hu * hv * w[a] * w[b] * p.S_u.cross(p.S_v).norm();
          }
        }
      }
    }
    EXPECT_NEAR(TrimmedArea(s) / direct, 1.0, 1e-10) << (rational ? "rational" : "polynomial");
  }
}

}  // namespace
}  // namespace tangent::nurbs
