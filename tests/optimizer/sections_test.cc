// A line contact's section row (SectionContactTerm): a cross-section circle of one cylinder
// against another cylinder lying beside it, parallel or nearly. Its value against dense sampling,
// its gradient against central differences of re-solved values, its Hessian against differences
// of the analytic gradient, all with quaternions off the unit sphere; and its regularity where the
// surface pair's own extremum is degenerate (exactly parallel cylinders: a line of minima).

#include "optimizer/sections.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "optimizer/problem.h"
#include "optimizer/step_reach.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kRadius = 0.01;  // m
constexpr double kLength = 0.1;

struct Pair {
  Mechanism mech;
  nurbs::NurbsSurface a = nurbs::MakeCylinder(kRadius, kLength);
  nurbs::NurbsSurface b = nurbs::MakeCylinder(1.01 * kRadius, kLength);
  Pair() {
    mech.AddBody(Body{"a"});
    mech.AddBody(Body{"b"});
  }
};

// Cylinder b beside a along x at `gap`, tilted by `tilt` about x (its axis leaves a's plane) and
// by `yaw` about y, both bodies moved a little; quaternions scaled off the unit sphere.
Eigen::VectorXd Place(double gap, double tilt, double yaw, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Quaterniond qa(1, 0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng));
  const Eigen::Vector3d pa(0.001 * u(rng), 0.001 * u(rng), 0.001 * u(rng));
  const Eigen::Quaterniond turn =
      Eigen::Quaterniond(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond qb = qa.normalized() * turn;
  // b's axis through (2.01 r + gap, 0, L/2) in a's frame, turned about that point.
  const Eigen::Vector3d mid(2.01 * kRadius + gap, 0, kLength / 2);
  const Eigen::Vector3d pb =
      pa + qa.normalized() * (mid - turn * Eigen::Vector3d(0, 0, kLength / 2));
  Eigen::VectorXd q(14);
  q << pa, 1.1 * qa.w(), 1.1 * qa.x(), 1.1 * qa.y(), 1.1 * qa.z(), pb, 0.9 * qb.w(), 0.9 * qb.x(),
      0.9 * qb.y(), 0.9 * qb.z();
  return q;
}

// The section's distance by sampling: a's circle at v = v0 against b, each circle point's
// signed distance to b by a point–surface solve (seeded from a grid of b), 720 points round the
// circle, then the best one's neighbourhood 720 times finer.
double SampledSectionDistance(const Pair& s, const Eigen::VectorXd& q, double v0) {
  std::vector<contact::BodyPose> poses;
  s.mech.Poses(q, &poses);
  auto to_b = [&](double u) {
    const Eigen::Vector3d x = poses[0].Point(s.a.Evaluate(u, v0, 0).S);
    double near = 1e9;
    Eigen::Vector2d seed(0, 0);
    for (int j = 0; j < 36; ++j) {
      for (int k = 0; k <= 20; ++k) {
        const Eigen::Vector2d st(j / 36.0, k / 20.0);
        const double d = (poses[1].Point(s.b.Evaluate(st[0], st[1], 0).S) - x).norm();
        if (d < near) {
          near = d;
          seed = st;
        }
      }
    }
    return contact::SolvePointSurface(x, s.b, poses[1], seed).distance;
  };
  double best = 1e9, at = 0.0;
  for (int i = 0; i < 720; ++i) {
    const double d = to_b(i / 720.0);
    if (d < best) {
      best = d;
      at = i / 720.0;
    }
  }
  const double centre = at;
  for (int i = -720; i <= 720; ++i) best = std::min(best, to_b(centre + i / (720.0 * 720.0)));
  return best;
}

TEST(SectionContactTest, ValueIsTheSectionsDistanceFromSampling) {
  Pair s;
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  std::mt19937_64 rng(7);
  for (double gap : {2e-4, 1e-5}) {
    const Eigen::VectorXd q = Place(gap, 0.02, 1e-4, rng);
    auto st = term->MakeState();
    auto& sec = static_cast<SectionContactTerm::State&>(*st);
    sec.Place(1, 0.3, Eigen::Vector3d(0.5, 0.3, 0.0));  // b's far side seed: (s, t, τ)
    Eigen::Matrix<double, 1, 14> grad;
    // A few evaluations to follow the extremum round from the seed.
    const double beta = testing::TermValue(s.mech, *term, st.get(), q, &grad);
    ASSERT_EQ(sec.ext.status, contact::ExtremalStatus::kConverged);
    EXPECT_NEAR(beta, SampledSectionDistance(s, q, 0.3), 1e-11) << "gap " << gap;
    EXPECT_GT(beta, 0.0);
  }
}

TEST(SectionContactTest, GradientAndHessianAgainstDifferences) {
  Pair s;
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  std::mt19937_64 rng(11);
  double worst_grad = 0.0, worst_hess = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    const double tilt = trial % 3 == 0 ? 0.0 : 0.05 * (trial % 4);  // 0: parallel
    const Eigen::VectorXd q = Place(1e-4 * (1 + trial % 3), tilt, 5e-4 * (trial % 2), rng);
    auto st = term->MakeState();
    auto& sec = static_cast<SectionContactTerm::State&>(*st);
    sec.Place(1, 0.2 + 0.05 * trial, Eigen::Vector3d(0.5, 0.2 + 0.05 * trial, 0.0));
    Eigen::Matrix<double, 1, 14> grad;
    testing::TermValue(s.mech, *term, st.get(), q, &grad);
    ASSERT_EQ(sec.ext.status, contact::ExtremalStatus::kConverged) << "trial " << trial;
    ASSERT_EQ(sec.ext.kind, contact::ExtremumKind::kMinimum)
        << "trial " << trial << " u " << sec.ext.u.transpose() << " beta " << sec.ext.beta;
    const Eigen::Matrix<double, 1, 14> fd =
        testing::ValueDifferences(s.mech, *term, st.get(), q, 1e-7);
    worst_grad =
        std::max(worst_grad, (fd - grad).cwiseAbs().maxCoeff() / grad.cwiseAbs().maxCoeff());
    const Eigen::Matrix<double, 14, 1> rows =
        testing::HessianRowErrors(s.mech, *term, st.get(), q, 1.7, 1e-6);
    worst_hess = std::max(worst_hess, rows.maxCoeff());
  }
  std::printf("section row: gradient %.1e, Hessian rows %.1e (relative, worst of 12)\n", worst_grad,
              worst_hess);
  EXPECT_LT(worst_grad, 1e-6);
  EXPECT_LT(worst_hess, 1e-6);
}

TEST(SectionContactTest, RegularWhereTheSurfacePairIsALineOfMinima) {
  // Exactly parallel: the pair's distance is constant along the axes, its Hessian singular; the
  // section's extremum is a regular minimum with the same distance.
  Pair s;
  std::mt19937_64 rng(3);
  const Eigen::VectorXd q = Place(1e-4, 0.0, 0.0, rng);
  std::vector<contact::BodyPose> poses;
  s.mech.Poses(q, &poses);
  const contact::SurfaceSurfaceExtremum pair = contact::SolveSurfaceSurface(
      s.a, poses[0], s.b, poses[1], Eigen::Vector4d(0.0, 0.5, 0.5, 0.5));
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  for (double v0 : {0.1, 0.5, 0.9}) {
    auto st = term->MakeState();
    auto& sec = static_cast<SectionContactTerm::State&>(*st);
    sec.Place(1, v0, Eigen::Vector3d(0.5, v0, 0.0));
    const double beta = testing::TermValue(s.mech, *term, st.get(), q, nullptr);
    EXPECT_EQ(sec.ext.kind, contact::ExtremumKind::kMinimum) << v0;
    EXPECT_NEAR(beta, pair.beta, 1e-12) << v0;
  }
}

TEST(SectionContactTest, ReachIsTheGapAndAQuarterOfTheSectionsRadius) {
  // The solver's step bound (Term::Reach): a's circle has radius r, so β + r/4, at the points'
  // midpoint.
  Pair s;
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  std::mt19937_64 rng(9);
  const Eigen::VectorXd q = Place(2e-4, 0.02, 0.0, rng);
  auto st = term->MakeState();
  auto& sec = static_cast<SectionContactTerm::State&>(*st);
  sec.Place(1, 0.4, Eigen::Vector3d(0.5, 0.4, 0.0));
  const double beta = testing::TermValue(s.mech, *term, st.get(), q, nullptr);
  Eigen::Vector3d p;
  double reach = 0.0;
  ASSERT_TRUE(term->Reach(st.get(), &p, &reach));
  EXPECT_NEAR(reach, beta + 0.25 * kRadius, 1e-12);
  EXPECT_LT((p - 0.5 * (sec.ext.p_f + sec.ext.p_g)).norm(), 1e-15);
  sec.Deactivate();
  EXPECT_FALSE(term->Reach(st.get(), &p, &reach));
}

TEST(SectionContactTest, AStepIsShortenedToTheRowsReach) {
  // ReachFraction (SolverOptions::step_reach): a 20 mm translation of a against b moves the
  // section's contact point 20 mm between the bodies; the step is cut to reach / 20 mm, and a
  // step within the reach is kept whole.
  Pair s;
  Problem problem(s.mech);
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  problem.AddInequality(term);
  ProblemData data(problem);
  auto& sec = data.Of(*term);
  sec.Place(1, 0.4, Eigen::Vector3d(0.5, 0.4, 0.0));
  std::mt19937_64 rng(13);
  const Eigen::VectorXd q = Place(2e-4, 0.0, 0.0, rng);
  testing::TermValue(s.mech, *term, &sec, q, nullptr);
  Eigen::Vector3d p;
  double reach = 0.0;
  ASSERT_TRUE(term->Reach(&sec, &p, &reach));
  Eigen::VectorXd step = Eigen::VectorXd::Zero(14);
  step[1] = 0.02;
  EXPECT_NEAR(ReachFraction(problem, data, q, step), reach / 0.02, 1e-12);
  step[1] = 0.5 * reach;
  EXPECT_EQ(ReachFraction(problem, data, q, step), 1.0);
  sec.Deactivate();
  step[1] = 0.02;
  EXPECT_EQ(ReachFraction(problem, data, q, step), 1.0);  // an inactive row bounds nothing
}

TEST(SectionContactTest, InactiveReadsFarWithNoGradient) {
  Pair s;
  auto term = MakeSectionContact(0, &s.a, 1, &s.b);
  auto st = term->MakeState();
  std::mt19937_64 rng(5);
  Eigen::Matrix<double, 1, 14> grad;
  const double beta = testing::TermValue(s.mech, *term, st.get(), Place(0.0, 0.0, 0.0, rng), &grad);
  EXPECT_EQ(beta, ContactSlotState::kInactiveDistance);
  EXPECT_TRUE(grad.isZero(0.0));
}

}  // namespace
}  // namespace tangent::optimizer
