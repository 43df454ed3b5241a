// Contact Jacobians: the implicit-function form, the closed form (seed 001 Appendix A, rederived)
// and Montana's formula, against central finite differences that re-solve the extremal point at
// q ± h; on orthogonal (sphere–plane, crossed cylinders), strongly non-orthogonal (sheared patch
// against a torus) and rational pairs, separated, touching and interpenetrating, under random
// poses. Also f_q, g_q and β_q (with β = 0), and the curve–surface version.

#include "contact/contact_jacobian.h"

#include <gtest/gtest.h>

#include <numbers>

#include "testing/contact_scenes.h"
#include "testing/random_nurbs.h"

namespace tangent::contact {
namespace {

using testing::Coordinates;

// h = 1e-6 on coordinates of size O(0.1 m) and O(1): central-difference truncation ~h²·|u'''|
// ~1e-10 relative and rounding ~1e-15/1e-6 = 1e-9 relative after Newton converges to ~1e-15.
// The bar, 1e-6 relative, leaves three digits of margin.
constexpr double kH = 1e-6;
constexpr double kRelTol = 1e-6;

double RelError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& ref) {
  return (a - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff();
}

struct FdResult {
  Matrix4x14 u_q;
  Matrix3x14 f_q, g_q;
  Row14 beta_q;
};

// Re-solves the pair at q ± h e_i from the converged point.
FdResult FiniteDifferences(const nurbs::NurbsSurface& f, const Vector7d& qf,
                           const nurbs::NurbsSurface& g, const Vector7d& qg,
                           const Eigen::Vector4d& u0) {
  FdResult r;
  for (int i = 0; i < 14; ++i) {
    SurfaceSurfaceExtremum e[2];
    for (int s = 0; s < 2; ++s) {
      Vector7d a = qf, b = qg;
      (i < 7 ? a[i] : b[i - 7]) += (s == 0 ? kH : -kH);
      e[s] =
          SolveSurfaceSurface(f, BodyPose::FromCoordinates(a), g, BodyPose::FromCoordinates(b), u0);
      EXPECT_EQ(e[s].status, ExtremalStatus::kConverged) << "FD solve, coordinate " << i;
    }
    r.u_q.col(i) = (e[0].u - e[1].u) / (2 * kH);
    r.f_q.col(i) = (e[0].p_f - e[1].p_f) / (2 * kH);
    r.g_q.col(i) = (e[0].p_g - e[1].p_g) / (2 * kH);
    r.beta_q(i) = (e[0].beta - e[1].beta) / (2 * kH);
  }
  return r;
}

struct Case {
  std::string name;
  const nurbs::NurbsSurface* f;
  const nurbs::NurbsSurface* g;
  Vector7d qf, qg;
  Eigen::Vector4d seed;
  bool orthogonal;
};

// Checks all forms at the pair's separated extremum, then touching (β = 0) and interpenetrating.
void CheckCase(const Case& c, double penetration) {
  SurfaceSurfaceExtremum e = SolveSurfaceSurface(*c.f, BodyPose::FromCoordinates(c.qf), *c.g,
                                                 BodyPose::FromCoordinates(c.qg), c.seed);
  ASSERT_EQ(e.status, ExtremalStatus::kConverged) << c.name;
  ASSERT_GT(e.beta, 0.0) << c.name << ": the case should start separated";
  Vector7d qg = c.qg;
  for (const double target : {e.beta, 0.0, -penetration}) {
    const std::string label = c.name + (target > 0    ? " separated"
                                        : target == 0 ? " touching"
                                                      : " interpenetrating");
    // Move G along the normal to the target β, re-solve (twice: the shift is first order).
    for (int k = 0; k < 3 && target != e.beta; ++k) {
      qg = testing::ShiftToBeta(e, qg, target);
      e = SolveSurfaceSurface(*c.f, BodyPose::FromCoordinates(c.qf), *c.g,
                              BodyPose::FromCoordinates(qg), e.u);
    }
    ASSERT_EQ(e.status, ExtremalStatus::kConverged) << label;
    if (target == 0.0) {
      EXPECT_LT(std::abs(e.beta), 1e-15) << label;
    }
    EXPECT_NEAR(e.alignment, -1.0, 1e-9) << label;
    const BodyPose pf = BodyPose::FromCoordinates(c.qf), pg = BodyPose::FromCoordinates(qg);
    nurbs::SpanHint hf, hg;
    SurfacePairEval ev;
    EvaluatePair(*c.f, pf, *c.g, pg, e.u, &hf, &hg, &ev);
    Matrix4x14 ift, closed, montana;
    ASSERT_TRUE(ContactJacobianImplicit(ev, pf, pg, &ift)) << label;
    ASSERT_TRUE(ContactJacobianClosedForm(ev, pf, pg, &closed)) << label;
    ASSERT_TRUE(ContactJacobianMontana(ev, pf, pg, &montana)) << label;
    const FdResult fd = FiniteDifferences(*c.f, c.qf, *c.g, qg, e.u);
    EXPECT_LT(RelError(ift, fd.u_q), kRelTol) << label << " implicit";
    EXPECT_LT(RelError(closed, fd.u_q), kRelTol) << label << " closed form";
    EXPECT_LT(RelError(montana, fd.u_q), kRelTol) << label << " Montana";
    EXPECT_LT(RelError(closed, ift), 1e-9) << label << " closed vs implicit";
    Matrix3x14 f_q, g_q;
    Row14 beta_q;
    PointAndDistanceJacobians(ev, pf, pg, closed, &f_q, &g_q, &beta_q);
    EXPECT_LT(RelError(f_q, fd.f_q), kRelTol) << label << " f_q";
    EXPECT_LT(RelError(g_q, fd.g_q), kRelTol) << label << " g_q";
    EXPECT_LT(RelError(beta_q, fd.beta_q), kRelTol) << label << " beta_q";
    if (target != 0.0) {  // The limit form equals (f − g)ᵀ(f_q − g_q)/β away from contact.
      const Row14 classic = ev.d.transpose() * (f_q - g_q) / e.beta;
      EXPECT_LT(RelError(classic, beta_q), 1e-10) << label;
    }
  }
}

TEST(JacobianTest, SpherePlaneOrthogonal) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0});
  std::mt19937_64 rng(20);
  for (int pose = 0; pose < 3; ++pose) {
    Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
    x.linear() = testing::RandomRotation(rng).toRotationMatrix();
    x.translation() = Eigen::Vector3d::Random();
    const Vector7d qf = testing::Transform(
        x, Coordinates({0.01, -0.02, 0.07},
                       Eigen::Quaterniond(
                           Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()) *
                           Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))));
    const Vector7d qg =
        testing::Transform(x, Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
    const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qg);
    CheckCase({"sphere-plane pose " + std::to_string(pose), &sphere, &plane, qf, qg,
               ClosestSamplePair(sphere, pf, plane, pg, 30), true},
              0.01);
  }
}

TEST(JacobianTest, CrossedCylindersOrthogonal) {
  const nurbs::NurbsSurface cyl = nurbs::MakeCylinder(0.01, 0.2);
  const Vector7d qf = Coordinates(
      {-0.1, 0, 0},
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY())));
  // Not quite crossed at 90°, so the extremum is not at a symmetric point.
  const Vector7d qg = Coordinates(
      {0.01, -0.1, 0.03},
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(-std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qg);
  CheckCase(
      {"crossed cylinders", &cyl, &cyl, qf, qg, ClosestSamplePair(cyl, pf, cyl, pg, 30), true},
      0.004);
}

TEST(JacobianTest, ShearedPatchAgainstTorusNonOrthogonal) {
  // Partials meeting at 15°: the strongly non-orthogonal case the closed form was derived for.
  const nurbs::NurbsSurface sheared =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, 0.01, true);
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.04, 0.01);
  std::mt19937_64 rng(21);
  for (int pose = 0; pose < 2; ++pose) {
    Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
    x.linear() = testing::RandomRotation(rng).toRotationMatrix();
    // The patch is turned over (its normal S_u × S_v now points down, facing the torus) and lies
    // over the torus tube's top (z = 0.01 at radius 0.04) with its dome hanging towards it;
    // F = patch (non-orthogonal), G = torus.
    const Vector7d qf = testing::Transform(
        x, Coordinates(
               {0.0, 0.0, 0.025},
               Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()))));
    const Vector7d qg =
        testing::Transform(x, Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
    const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qg);
    CheckCase({"sheared-torus pose " + std::to_string(pose), &sheared, &torus, qf, qg,
               ClosestSamplePair(sheared, pf, torus, pg, 40), false},
              0.002);
    // And with the roles swapped (the torus as f, the sheared patch as g).
    CheckCase({"torus-sheared pose " + std::to_string(pose), &torus, &sheared, qg, qf,
               ClosestSamplePair(torus, pg, sheared, pf, 40), false},
              0.002);
  }
}

TEST(JacobianTest, RandomRationalBicubicAgainstSphere) {
  std::mt19937_64 rng(22);
  // A gently curved rational bicubic sheet (net spacing 1 per control point, scaled to 2 cm).
  const nurbs::NurbsSurface raw = nurbs::testing::RandomSurface(rng, 3, 3, 6, 6, true);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  for (int i = 0; i < raw.num_u(); ++i) {
    for (int j = 0; j < raw.num_v(); ++j) {
      Eigen::Vector3d p = raw.point(i, j);
      p.z() *= 0.1;  // Flatter than the generator's default, so the sphere meets one extremum.
      pts.push_back(0.02 * p);
      w.push_back(raw.weight(i, j));
    }
  }
  const nurbs::NurbsSurface sheet(raw.knots_u(), raw.knots_v(), pts, w);
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.02);
  const Eigen::Vector3d mid =
      sheet
          .Evaluate(0.5 * (sheet.knots_u().domain_begin() + sheet.knots_u().domain_end()),
                    0.5 * (sheet.knots_v().domain_begin() + sheet.knots_v().domain_end()), 0)
          .S;
  const Vector7d qf = Coordinates(
      mid + Eigen::Vector3d(0.002, -0.003, 0.03),
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  const Vector7d qg = Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qg);
  CheckCase({"sphere-rational sheet", &sphere, &sheet, qf, qg,
             ClosestSamplePair(sphere, pf, sheet, pg, 30), false},
            0.003);
}

TEST(JacobianTest, CurveSurfaceClosedFormAndImplicitMatchFiniteDifferences) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const double c45 = std::sqrt(0.5);
  const std::vector<Eigen::Vector3d> pts = {
      {0.03 * c45, -0.03 * c45, 0}, {0.03 / c45, 0, 0}, {0.03 * c45, 0.03 * c45, 0}};
  const nurbs::NurbsCurve3d arc(nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}), pts, {1.0, c45, 1.0});
  // Also a trimming-style curve: a line in the parameter domain of a sheared patch on body G.
  const nurbs::NurbsSurface sheared =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, -0.01, false);
  const nurbs::NurbsCurve2d trim(nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}),
                                 {{0.1, 0.2}, {0.5, 0.6}, {0.9, 0.4}});
  const BodyCurve curves[2] = {BodyCurve(&arc), BodyCurve(&sheared, &trim)};
  const Vector7d qf = Coordinates(
      {0.01, -0.02, 0.0},
      Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  const Vector7d qgs[2] = {
      Coordinates({-0.04, -0.02, 0.08},
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()))),
      Coordinates({-0.03, -0.05, 0.07},
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())))};
  for (int c = 0; c < 2; ++c) {
    const BodyPose pf = BodyPose::FromCoordinates(qf), pg = BodyPose::FromCoordinates(qgs[c]);
    // Seed: best of a coarse scan over the curve and the sphere's upper half.
    Eigen::Vector3d seed;
    double best = INFINITY;
    for (int a = 0; a < 40; ++a)
      for (int b = 0; b < 20; ++b)
        for (int t = 0; t <= 20; ++t) {
          const Eigen::Vector3d u(a / 40.0, 0.1 + 0.8 * b / 20.0, t / 20.0);
          int sp = 0;
          nurbs::SpanHint sh;
          const double d = (pf.Point(sphere.Evaluate(u[0], u[1], 0).S) -
                            pg.Point(curves[c].Evaluate(u[2], &sp, &sh).C))
                               .norm();
          if (d < best) {
            best = d;
            seed = u;
          }
        }
    const CurveSurfaceExtremum e = SolveCurveSurface(sphere, pf, curves[c], pg, seed);
    ASSERT_EQ(e.status, ExtremalStatus::kConverged) << "curve " << c;
    nurbs::SpanHint hf, hg;
    int span = 0;
    CurveSurfaceEval ev;
    EvaluateCurveSurface(sphere, pf, curves[c], pg, e.u, &hf, &span, &hg, &ev);
    Matrix3x14 ift, closed, fd;
    ASSERT_TRUE(CurveSurfaceJacobianImplicit(ev, pf, pg, &ift));
    ASSERT_TRUE(CurveSurfaceJacobianClosedForm(ev, pf, pg, &closed));
    for (int i = 0; i < 14; ++i) {
      Eigen::Vector3d u[2];
      for (int s = 0; s < 2; ++s) {
        Vector7d a = qf, b = qgs[c];
        (i < 7 ? a[i] : b[i - 7]) += (s == 0 ? kH : -kH);
        u[s] = SolveCurveSurface(sphere, BodyPose::FromCoordinates(a), curves[c],
                                 BodyPose::FromCoordinates(b), e.u)
                   .u;
      }
      fd.col(i) = (u[0] - u[1]) / (2 * kH);
    }
    EXPECT_LT(RelError(ift, fd), kRelTol) << "curve " << c << " implicit";
    EXPECT_LT(RelError(closed, fd), kRelTol) << "curve " << c << " closed form";
  }
}

}  // namespace
}  // namespace tangent::contact
