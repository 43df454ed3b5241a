// Extremal-distance solvers on configurations with analytic answers, under several world poses
// (frame invariance), with classification, domain boundaries and bad seeds.

#include "contact/extremal.h"

#include <gtest/gtest.h>

#include <numbers>

#include "nurbs/primitives.h"
#include "testing/contact_scenes.h"

namespace tangent::contact {
namespace {

using nurbs::MakeCylinder;
using nurbs::MakePlanePatch;
using nurbs::MakeSphere;
using testing::Coordinates;
using testing::RandomRotation;
using testing::Transform;

// Positions are O(0.1 m); Newton converges to the rounding level, ~1e-16 m; 1e-13 m leaves
// room for the conditioning of the pair (curvature radii of 1-5 cm).
constexpr double kPosTol = 1e-13;

// Sphere of radius r on body F whose poles point along x (so the lowest point is on the
// equator, away from the degenerate pole), above the plane patch z = 0 on body G.
struct SpherePlane {
  nurbs::NurbsSurface sphere = MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  nurbs::NurbsSurface plane = MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0});
  Vector7d Sphere(double height) const {
    return Coordinates({0.01, -0.02, height}, Eigen::Quaterniond(Eigen::AngleAxisd(
                                                  std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  }
  Vector7d Plane() const {
    return Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  }
};

TEST(ExtremalTest, SpherePlaneSeparatedTouchingAndPenetratingUnderManyPoses) {
  const SpherePlane sp;
  std::mt19937_64 rng(10);
  for (double height : {0.08, 0.05, 0.03}) {  // β = 0.03, 0, −0.02
    for (int pose = 0; pose < 6; ++pose) {
      Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
      if (pose > 0) {
        x.linear() = RandomRotation(rng).toRotationMatrix();
        x.translation() = Eigen::Vector3d::Random();
      }
      const BodyPose pf = BodyPose::FromCoordinates(Transform(x, sp.Sphere(height)));
      const BodyPose pg = BodyPose::FromCoordinates(Transform(x, sp.Plane()));
      // Seed 0.02 (in parameters) off the lowest point: longitude 0.75 (−y body = −z world after
      // the 90° turn about x), latitude 0.5, plane point under the centre.
      const Eigen::Vector4d seed(0.73, 0.52, 0.5 + 0.01 / 0.4 + 0.02, 0.5 - 0.02 / 0.4 - 0.02);
      const SurfaceSurfaceExtremum e = SolveSurfaceSurface(sp.sphere, pf, sp.plane, pg, seed);
      ASSERT_EQ(e.status, ExtremalStatus::kConverged) << ToString(e.status) << " h=" << height;
      EXPECT_NEAR(e.beta, height - 0.05, kPosTol) << "pose " << pose;
      EXPECT_NEAR(e.alignment, -1.0, 1e-14);
      // Contact frames: orthonormal, right-handed, z the outward normals (g's up, f's down).
      for (const Eigen::Matrix3d* fr : {&e.R_WCf, &e.R_WCg}) {
        EXPECT_LT((fr->transpose() * *fr - Eigen::Matrix3d::Identity()).norm(), 1e-14);
        EXPECT_NEAR(fr->determinant(), 1.0, 1e-14);
      }
      EXPECT_LT((e.R_WCg.col(2) - x.linear() * Eigen::Vector3d::UnitZ()).norm(), 1e-14);
      EXPECT_LT((e.R_WCf.col(2) + x.linear() * Eigen::Vector3d::UnitZ()).norm(), 1e-12);
      const Eigen::Vector3d expect_g = x * Eigen::Vector3d(0.01, -0.02, 0.0);
      EXPECT_LT((e.p_g - expect_g).norm(), kPosTol);
      EXPECT_LT((e.p_f - (expect_g + x.linear() * Eigen::Vector3d(0, 0, height - 0.05))).norm(),
                kPosTol);
      // Apart: a minimum of the distance; interpenetrating: the deepest point is a saddle of
      // ½|d|² (a maximum along the sphere, a minimum along the plane).
      if (height > 0.05) {
        EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
      } else if (height < 0.05) {
        EXPECT_EQ(e.kind, ExtremumKind::kSaddle);
      }
      EXPECT_LE(e.iterations, 8);
    }
  }
}

TEST(ExtremalTest, CrossedCylindersMatchSkewLineDistance) {
  // Two cylinders of radius 1 cm, axes along world x (at z = 0) and y (at z = c): the extremal
  // distance is c − 2 r for any c, including c < 2r (interpenetrating).
  const nurbs::NurbsSurface cyl = MakeCylinder(0.01, 0.2);
  for (double c : {0.05, 0.02, 0.015}) {
    // Cylinder axis is body z from 0 to 0.2; turn it to world x (F) and world y (G).
    const Vector7d qf = Coordinates(
        {-0.1, 0, 0},
        Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY())));
    const Vector7d qg = Coordinates(
        {0, -0.1, c},
        Eigen::Quaterniond(Eigen::AngleAxisd(-std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
    const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qg);
    const Eigen::Vector4d seed = ClosestSamplePair(cyl, pf, cyl, pg, 24);
    const SurfaceSurfaceExtremum e = SolveSurfaceSurface(cyl, pf, cyl, pg, seed);
    ASSERT_EQ(e.status, ExtremalStatus::kConverged) << ToString(e.status);
    EXPECT_NEAR(std::abs(e.beta), std::abs(c - 0.02), kPosTol) << "c=" << c;
    EXPECT_NEAR(e.p_f.z(), 0.01, kPosTol);
    EXPECT_NEAR(e.p_g.z(), c - 0.01, kPosTol);
  }
}

TEST(ExtremalTest, LeavingTheDomainStopsOnTheBoundary) {
  // A small plane patch [0.05, 0.15] x [-0.05, 0.05] next to the sphere's footprint: the
  // closest pair wants x < 0.05 on the patch, so the solver holds s on its lower bound.
  const SpherePlane sp;
  const nurbs::NurbsSurface patch = MakePlanePatch({0.05, -0.05, 0}, {0.1, 0, 0}, {0, 0.1, 0});
  const BodyPose pf = BodyPose::FromCoordinates(sp.Sphere(0.06));
  const BodyPose pg = BodyPose::FromCoordinates(sp.Plane());
  const SurfaceSurfaceExtremum e =
      SolveSurfaceSurface(sp.sphere, pf, patch, pg, Eigen::Vector4d(0.75, 0.5, 0.5, 0.5));
  EXPECT_EQ(e.status, ExtremalStatus::kAtBoundary);
  EXPECT_TRUE(e.at_bound[2]);
  EXPECT_EQ(e.u[2], 0.0);
  EXPECT_FALSE(e.at_bound[3]);
  // Restricted extremum: the point of the edge x = 0.05 closest to the sphere.
  EXPECT_NEAR(e.p_g.x(), 0.05, 1e-15);
  EXPECT_NEAR(e.p_g.y(), -0.02, 1e-12);
  const Eigen::Vector3d c(0.01, -0.02, 0.06);
  EXPECT_NEAR((e.p_f - c).norm(), 0.05, 1e-12);
  EXPECT_NEAR((e.p_f - c).normalized().dot((e.p_g - c).normalized()), 1.0, 1e-12);
}

TEST(ExtremalTest, ClosedSurfacesWrapAcrossTheirSeam) {
  // Which primitives are periodic (closed with a C¹ seam), and a point-surface solve on a
  // cylinder seeded on one side of its seam whose answer lies on the other: the longitude wraps
  // instead of stopping on the domain edge.
  const nurbs::NurbsSurface cylinder = MakeCylinder(0.02, 0.1);
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.05, 0.01);
  const nurbs::NurbsSurface sphere = MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface tube =
      nurbs::MakeTube(nurbs::PaperclipPath(), nurbs::kPaperclipWireRadius);
  EXPECT_TRUE(cylinder.periodic_u());
  EXPECT_FALSE(cylinder.periodic_v());
  EXPECT_TRUE(torus.periodic_u());
  EXPECT_TRUE(torus.periodic_v());
  EXPECT_TRUE(sphere.periodic_u());
  EXPECT_FALSE(sphere.periodic_v());
  EXPECT_FALSE(tube.periodic_u());
  EXPECT_TRUE(tube.periodic_v());
  const SpherePlane sp;
  EXPECT_FALSE(sp.plane.periodic_u() || sp.plane.periodic_v());
  const BodyPose pose = BodyPose::FromCoordinates(
      Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
  // The target: 1 cm outside the cylinder at longitude u = 0.01; the seed at u = 0.98.
  const Eigen::Vector3d on = cylinder.Evaluate(0.01, 0.5, 0).S;
  const Eigen::Vector3d target = on + 0.01 * Eigen::Vector3d(on.x(), on.y(), 0).normalized();
  const PointSurfaceExtremum e = SolvePointSurface(target, cylinder, pose, {0.98, 0.5});
  EXPECT_EQ(e.status, ExtremalStatus::kConverged);
  EXPECT_FALSE(e.at_bound[0]);
  EXPECT_NEAR(e.u[0], 0.01, 1e-12);
  EXPECT_NEAR(e.distance, 0.01, kPosTol);
}

TEST(ExtremalTest, SeedsOutsideTheDomainAreClampedAndResultsStayInside) {
  const SpherePlane sp;
  const BodyPose pf = BodyPose::FromCoordinates(sp.Sphere(0.07));
  const BodyPose pg = BodyPose::FromCoordinates(sp.Plane());
  const SurfaceSurfaceExtremum e =
      SolveSurfaceSurface(sp.sphere, pf, sp.plane, pg, Eigen::Vector4d(5, -3, 2, -7));
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(e.u[i], 0.0);
    EXPECT_LE(e.u[i], 1.0);
  }
}

TEST(ExtremalTest, PointSurfaceOnSphereAndPlane) {
  const SpherePlane sp;
  const BodyPose pf = BodyPose::FromCoordinates(sp.Sphere(0.3));
  const Eigen::Vector3d center(0.01, -0.02, 0.3);
  std::mt19937_64 rng(11);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d dir = Eigen::Vector3d::Random().normalized();
    const double r = 0.02 + 0.06 * (k % 4);  // Inside and outside the sphere.
    const Eigen::Vector3d x = center + r * dir;
    // Seed from the direction in the body frame, a little off.
    const Eigen::Vector3d b = pf.R_WB.transpose() * dir;
    double lon = std::atan2(b.y(), b.x()) / (2 * std::numbers::pi);
    if (lon < 0) lon += 1;
    const double lat = 0.5 + std::asin(std::clamp(b.z(), -1.0, 1.0)) / std::numbers::pi;
    if (lat < 0.1 || lat > 0.9) continue;  // Poles: the parameterization is degenerate.
    const PointSurfaceExtremum e = SolvePointSurface(x, sp.sphere, pf, {lon + 0.02, lat - 0.02});
    ASSERT_EQ(e.status, ExtremalStatus::kConverged);
    EXPECT_NEAR(e.distance, r - 0.05, kPosTol);
    EXPECT_LT((e.p_f - (center + 0.05 * dir)).norm(), kPosTol);
  }
}

TEST(ExtremalTest, CurveSurfaceArcAboveSphere) {
  // A 90° arc of radius 3 cm (from −45° to 45° about its centre) in the plane 8 cm above a
  // sphere of radius 5 cm, its centre 5 cm to the −x side of the sphere's: the arc's point
  // nearest the sphere is its middle, 2 cm off the axis, so β = √(0.02² + 0.08²) − 0.05.
  const SpherePlane sp;
  const double c45 = std::sqrt(0.5);
  const std::vector<Eigen::Vector3d> pts = {
      {0.03 * c45, -0.03 * c45, 0}, {0.03 / c45, 0, 0}, {0.03 * c45, 0.03 * c45, 0}};
  const nurbs::NurbsCurve3d arc(nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}), pts, {1.0, c45, 1.0});
  const BodyCurve curve(&arc);
  const BodyPose pf = BodyPose::FromCoordinates(sp.Sphere(0.0));
  const BodyPose pg = BodyPose::FromCoordinates(
      Coordinates({0.01 - 0.05, -0.02, 0.08}, Eigen::Quaterniond::Identity()));
  // Seed near the sphere's top (longitude 0.25 is body +y = world +z after the turn about x).
  const CurveSurfaceExtremum e = SolveCurveSurface(sp.sphere, pf, curve, pg, {0.27, 0.45, 0.4});
  ASSERT_EQ(e.status, ExtremalStatus::kConverged) << ToString(e.status);
  EXPECT_NEAR(e.beta, std::hypot(0.02, 0.08) - 0.05, kPosTol);
  EXPECT_NEAR(e.u[2], 0.5, 1e-12);
  EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
}

// The parameter distance (periodic directions the short way round) and the rule that tells a
// re-solve that found another extremum of the pair from the contact moved: far (beyond
// kMaxResolveJump) and farther apart than the two points at the start now are.
TEST(ExtremalTest, ParameterDistanceAndAnotherExtremum) {
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.05, 0.01);  // periodic both ways
  const nurbs::NurbsSurface patch = nurbs::MakeShearedPatch(0.3, 0.2, 0.01, true);  // [0,1]²
  ASSERT_TRUE(torus.periodic_u() && torus.periodic_v());
  ASSERT_FALSE(patch.periodic_u() || patch.periodic_v());
  const Eigen::Vector4d x(0.99, 0.5, 0.2, 0.5);
  // Across the torus seam 0.99 → 0.02 is 0.03 of the domain, not 0.97; the patch's 0.2 → 0.9
  // is 0.7.
  EXPECT_NEAR(ParameterDistance(torus, patch, x, Eigen::Vector4d(0.02, 0.5, 0.2, 0.5)), 0.03,
              1e-15);
  EXPECT_NEAR(ParameterDistance(torus, patch, x, Eigen::Vector4d(0.99, 0.5, 0.9, 0.5)), 0.7, 1e-15);
  SurfaceSurfaceExtremum far_and_farther, far_and_nearer, near_and_farther;
  far_and_farther.u = far_and_nearer.u = Eigen::Vector4d(0.99, 0.5, 0.3, 0.5);
  near_and_farther.u = Eigen::Vector4d(0.02, 0.5, 0.2, 0.5);
  far_and_farther.beta = near_and_farther.beta = 2e-3;
  far_and_nearer.beta = 1e-4;
  const double held_distance = 1e-3;
  EXPECT_TRUE(FoundAnotherExtremum(torus, patch, x, far_and_farther, held_distance));
  EXPECT_FALSE(FoundAnotherExtremum(torus, patch, x, far_and_nearer, held_distance));
  EXPECT_FALSE(FoundAnotherExtremum(torus, patch, x, near_and_farther, held_distance));
}

}  // namespace
}  // namespace tangent::contact
