// The hard cases of design.md §4.3, each with its defined behaviour. Every test prints the
// figures docs/stability.md quotes (run: ./build/tests/contact/hard_cases_test).

#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>

#include "contact/contact_jacobian.h"
#include "contact/tracker.h"
#include "testing/contact_scenes.h"

namespace tangent::contact {
namespace {

using testing::Coordinates;
using testing::Paraboloid;

const Vector7d kIdentity = Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());

TEST(HardCasesTest, FocalPoint) {
  // Point on the axis of a paraboloid with vertex curvature radius 2 cm: below the focal
  // height the vertex is a distance minimum, above it a maximum, at it a degenerate extremum.
  const double k = 50.0;  // 1/k = 2 cm
  const nurbs::NurbsSurface par = Paraboloid(k, 0.02);
  const BodyPose pose = BodyPose::FromCoordinates(kIdentity);
  const Eigen::Vector2d seed(0.52, 0.47);
  const PointSurfaceExtremum below = SolvePointSurface({0, 0, 0.9 / k}, par, pose, seed);
  const PointSurfaceExtremum above = SolvePointSurface({0, 0, 1.1 / k}, par, pose, seed);
  const PointSurfaceExtremum focal = SolvePointSurface({0, 0, 1.0 / k}, par, pose, seed);
  EXPECT_EQ(below.status, ExtremalStatus::kConverged);
  EXPECT_EQ(below.kind, ExtremumKind::kMinimum);
  EXPECT_EQ(above.status, ExtremalStatus::kConverged);
  EXPECT_EQ(above.kind, ExtremumKind::kMaximum);
  // At the focal point the Hessian vanishes: Newton slows to linear convergence and the solver
  // says so; the point is still the vertex to ~the cube root of the step tolerance.
  EXPECT_EQ(focal.status, ExtremalStatus::kSingular);
  EXPECT_EQ(focal.kind, ExtremumKind::kDegenerate);
  const double err = (focal.u - Eigen::Vector2d(0.5, 0.5)).norm();
  EXPECT_LT(err, 1e-4);
  std::printf(
      "focal point (point-surface): status %s, kind %s, |u - vertex| = %.1e, %d iterations\n",
      ToString(focal.status), ToString(focal.kind), err, focal.iterations);
  // Surface pair: a 5 mm sphere centred at the focal point, i.e. its lowest point at a distance
  // equal to the vertex's radius of curvature less 5 mm: the pair's ∂F/∂u is singular; the
  // solver says so and both Jacobian forms refuse rather than return a huge u_q.
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.005);
  const Vector7d q_ball = Coordinates(
      {0, 0, 1.0 / k},
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  const BodyPose pb = BodyPose::FromCoordinates(q_ball);
  const SurfaceSurfaceExtremum pair =
      SolveSurfaceSurface(ball, pb, par, pose, {0.74, 0.52, 0.52, 0.48});
  EXPECT_EQ(pair.status, ExtremalStatus::kSingular);
  nurbs::SpanHint h1, h2;
  SurfacePairEval ev;
  EvaluatePair(ball, pb, par, pose, pair.u, &h1, &h2, &ev);
  Matrix4x14 uq;
  EXPECT_FALSE(ContactJacobianImplicit(ev, pb, pose, &uq));
  EXPECT_FALSE(ContactJacobianClosedForm(ev, pb, pose, &uq));
  EXPECT_TRUE(uq.allFinite());
  std::printf(
      "focal point (sphere-paraboloid): status %s, beta = %.6e (expected %.6e), rcond %.1e\n",
      ToString(pair.status), pair.beta, 1.0 / k - 0.005, pair.rcond);
  EXPECT_NEAR(pair.beta, 1.0 / k - 0.005, 1e-7);
}

TEST(HardCasesTest, ContinuumOfExtremalPairs) {
  const BodyPose id = BodyPose::FromCoordinates(kIdentity);
  struct Case {
    const char* name;
    nurbs::NurbsSurface f, g;
    Eigen::Vector4d seed;
    double beta;
  };
  const Case cases[] = {
      {"concentric spheres",
       nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.03),
       nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
       {0.3, 0.45, 0.32, 0.47},
       -0.02},
      {"coaxial cylinders",
       nurbs::MakeCylinder(0.02, 0.1),
       nurbs::MakeCylinder(0.05, 0.1),
       {0.3, 0.4, 0.31, 0.45},
       -0.03},
      {"plane on plane",
       nurbs::MakePlanePatch({0, 0, 0.01}, {0.1, 0, 0}, {0, -0.1, 0}),
       nurbs::MakePlanePatch({0, -0.1, 0}, {0.1, 0, 0}, {0, 0.1, 0}),
       {0.3, 0.4, 0.35, 0.5},
       0.01},
  };
  for (const Case& c : cases) {
    const SurfaceSurfaceExtremum e = SolveSurfaceSurface(c.f, id, c.g, id, c.seed);
    // A valid extremal pair (one of infinitely many), flagged singular; never NaN.
    EXPECT_EQ(e.status, ExtremalStatus::kSingular) << c.name;
    EXPECT_NEAR(e.beta, c.beta, 1e-12) << c.name;
    EXPECT_TRUE(e.u.allFinite());
    ContactTracker t(c.f, c.g);
    EXPECT_EQ(t.Reset(kIdentity, kIdentity, e.u), TrackStatus::kSingular) << c.name;
    std::printf("%s: status %s, beta %.3e (exact %.3e), |moved from seed| = %.1e\n", c.name,
                ToString(e.status), e.beta, c.beta, (e.u - c.seed).norm());
  }
}

TEST(HardCasesTest, PoleOfARevolvedSurface) {
  // The sphere's south pole (v = 0, where S_u = 0) resting above a plane: the extremum sits on
  // the domain edge v = 0 with a degenerate parameterization.
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0});
  const BodyPose pf =
      BodyPose::FromCoordinates(Coordinates({0.01, 0.02, 0.06}, Eigen::Quaterniond::Identity()));
  const BodyPose pg = BodyPose::FromCoordinates(kIdentity);
  const SurfaceSurfaceExtremum e =
      SolveSurfaceSurface(sphere, pf, plane, pg, {0.3, 0.03, 0.5, 0.5});
  // Newton alone is only linear at the pole (S_u = 0: the contact equations lose rank) and
  // stops singular ~1e-7 m away; the pole handling (extremal.cc) recognises the pole itself as
  // the minimum (no departure from it lowers the distance) and returns it exactly, converged,
  // with the frame from the limit normal (tests/contact/pole_test.cc covers seeds on and around
  // poles and tilted planes). u_q at the pole is refused or finite (it grows like 1/v nearby).
  EXPECT_EQ(e.status, ExtremalStatus::kConverged);
  EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
  EXPECT_NEAR(e.beta, 0.01, 1e-15);
  EXPECT_LT((e.p_f - Eigen::Vector3d(0.01, 0.02, 0.01)).norm(), 1e-15);
  EXPECT_LT((e.R_WCf.col(2) + Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  nurbs::SpanHint h1, h2;
  SurfacePairEval ev;
  EvaluatePair(sphere, pf, plane, pg, e.u, &h1, &h2, &ev);
  Matrix4x14 uq;
  if (ContactJacobianClosedForm(ev, pf, pg, &uq)) {
    EXPECT_TRUE(uq.allFinite());
  }
  std::printf("pole: status %s, beta %.3e (exact 1e-2), point error %.1e\n", ToString(e.status),
              e.beta, (e.p_f - Eigen::Vector3d(0.01, 0.02, 0.01)).norm());
}

TEST(HardCasesTest, PartialsMeetingAtAFewDegrees) {
  // A patch sheared to 3°, face down over a torus: the closed form still matches finite
  // differences; print how well.
  const nurbs::NurbsSurface sheared =
      nurbs::MakeShearedPatch(3 * std::numbers::pi / 180, 0.08, 0.01, false);
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.04, 0.01);
  const Vector7d qf = Coordinates(
      {-0.03, 0.0, 0.025},
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX())));
  const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(kIdentity);
  const SurfaceSurfaceExtremum e =
      SolveSurfaceSurface(sheared, pf, torus, pg, ClosestSamplePair(sheared, pf, torus, pg, 60));
  ASSERT_EQ(e.status, ExtremalStatus::kConverged);
  nurbs::SpanHint h1, h2;
  SurfacePairEval ev;
  EvaluatePair(sheared, pf, torus, pg, e.u, &h1, &h2, &ev);
  Matrix4x14 closed, ift, fd;
  ASSERT_TRUE(ContactJacobianClosedForm(ev, pf, pg, &closed));
  ASSERT_TRUE(ContactJacobianImplicit(ev, pf, pg, &ift));
  const double h = 1e-6;
  for (int i = 0; i < 14; ++i) {
    Eigen::Vector4d u[2];
    for (int s = 0; s < 2; ++s) {
      Vector7d a = qf, b = kIdentity;
      (i < 7 ? a[i] : b[i - 7]) += (s == 0 ? h : -h);
      u[s] = SolveSurfaceSurface(sheared, BodyPose::FromCoordinates(a), torus,
                                 BodyPose::FromCoordinates(b), e.u)
                 .u;
    }
    fd.col(i) = (u[0] - u[1]) / (2 * h);
  }
  const double err_closed = (closed - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff();
  const double err_ift = (ift - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff();
  EXPECT_LT(err_closed, 1e-6);
  EXPECT_LT(err_ift, 1e-6);
  const Eigen::Vector3d su = ev.f.world.S_u.normalized(), sv = ev.f.world.S_v.normalized();
  std::printf("partials at %.2f deg: closed form vs FD %.1e, implicit vs FD %.1e\n",
              std::acos(std::abs(su.dot(sv))) * 180 / std::numbers::pi, err_closed, err_ift);
}

TEST(HardCasesTest, DeepInterpenetration) {
  // Sphere of radius 5 cm whose centre is 3 cm *below* the plane: the penetration extremum is
  // the sphere's lowest point against the plane point above it, β = −8 cm (deeper than the
  // radius), normals anti-parallel; a saddle of ½|d|².
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0});
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  const BodyPose pf = BodyPose::FromCoordinates(Coordinates({0, 0, -0.03}, turn));
  const BodyPose pg = BodyPose::FromCoordinates(kIdentity);
  int found = 0;
  for (double off : {0.0, 0.01, 0.02, 0.04}) {
    const SurfaceSurfaceExtremum e =
        SolveSurfaceSurface(sphere, pf, plane, pg, {0.75 + off, 0.5 - off, 0.5 + off, 0.5 - off});
    if (e.status == ExtremalStatus::kConverged && std::abs(e.beta + 0.08) < 1e-12) ++found;
    if (off == 0.02) {
      EXPECT_EQ(e.status, ExtremalStatus::kConverged);
      EXPECT_NEAR(e.beta, -0.08, 1e-12);
      EXPECT_NEAR(e.alignment, -1.0, 1e-12);
      EXPECT_EQ(e.kind, ExtremumKind::kSaddle);
    }
  }
  std::printf(
      "deep interpenetration: penetration extremum (beta = -8 cm) found from %d of 4 seeds\n",
      found);
}

}  // namespace
}  // namespace tangent::contact
