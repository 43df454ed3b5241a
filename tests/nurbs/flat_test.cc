// Flat quadrilateral faces (nurbs/flat.h): which surfaces are held by their corners.

#include "nurbs/flat.h"

#include <gtest/gtest.h>

#include <numbers>

#include <Eigen/Geometry>

#include "nurbs/primitives.h"
#include "nurbs/refinement.h"

namespace tangent::nurbs {
namespace {

// A biquadratic patch over a 20 mm square in the plane z = 0, its boundary's middle points at
// `bulge` off the edges' lines in the plane (a curved edge), its centre `lift` off the plane,
// rational when `weight` is not 1.
NurbsSurface Biquadratic(double bulge, double lift, double weight) {
  const KnotVector k(2, {0, 0, 0, 1, 1, 1});
  std::vector<Eigen::Vector3d> p;
  std::vector<double> w;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d x(10e-3 * i, 10e-3 * j, 0.0);
      if (i == 1 && j == 0) x.y() -= bulge;
      if (i == 1 && j == 1) x.z() += lift;
      p.push_back(x);
      w.push_back(i == 1 && j == 1 ? weight : 1.0);
    }
  }
  return NurbsSurface(k, k, p, w);
}

TEST(FlatTest, PlanePatchesAndFlatNetsAreQuadsWithTheirCorners) {
  const Eigen::Vector3d o(-0.01, 0.02, 0.005), eu(0.02, 0.0, 0.001), ev(0.0, 0.03, -0.002);
  const auto q = FlatQuadOf(MakePlanePatch(o, eu, ev));
  ASSERT_TRUE(q.has_value());
  const Eigen::Vector3d expected[4] = {o, o + eu, o + eu + ev, o + ev};
  for (int k = 0; k < 4; ++k) {
    EXPECT_LT((q->points[k] - expected[k]).norm(), 1e-16);
    EXPECT_EQ(q->corners[k], Eigen::Vector2d(k == 1 || k == 2, k >= 2));
  }
  // Refined and placed, still flat; a rational flat net too (weights move points along the
  // plane only).
  const NurbsSurface refined = InsertKnot(MakePlanePatch(o, eu, ev), Direction::kU, 0.3);
  EXPECT_TRUE(FlatQuadOf(Transformed(refined, Eigen::Isometry3d(Eigen::AngleAxisd(
                                                  0.7, Eigen::Vector3d(1, 2, 3).normalized()))))
                  .has_value());
  EXPECT_TRUE(FlatQuadOf(Biquadratic(0.0, 0.0, 2.5)).has_value());
  EXPECT_TRUE(FlatQuadOf(MakeShearedPatch(0.3, 0.05, 0.0, false)).has_value());
}

TEST(FlatTest, CurvedFacesCurvedEdgesAndClosedSurfacesAreNot) {
  EXPECT_FALSE(FlatQuadOf(Biquadratic(0.0, 1e-6, 1.0)).has_value());  // 1 µm off the plane
  EXPECT_FALSE(FlatQuadOf(Biquadratic(1e-6, 0.0, 1.0)).has_value());  // an edge bowed in-plane
  EXPECT_FALSE(FlatQuadOf(MakeShearedPatch(0.3, 0.05, 0.01, false)).has_value());
  EXPECT_FALSE(FlatQuadOf(MakeCylinder(0.01, 0.02)).has_value());
  EXPECT_FALSE(FlatQuadOf(MakeSphere(Eigen::Vector3d::Zero(), 0.01)).has_value());
}

}  // namespace
}  // namespace tangent::nurbs
