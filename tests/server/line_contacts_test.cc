// The servo's line contacts (server/line_contacts.h): two cylinders nearly side by side (a line
// contact: relative curvature nearly zero along the axes) get two sections either side of the
// contact, each measuring the same gap; two crossing at right angles (a point contact) get none;
// the choice has hysteresis; and following a contact allocates nothing.

#include "server/line_contacts.h"

#include <gtest/gtest.h>

#include <cmath>

#include "contact/relative_curvature.h"
#include "nurbs/primitives.h"
#include "optimizer/solver.h"
#include "testing/alloc_counter.h"

namespace tangent::server {
namespace {

constexpr double kRadius = 0.01, kLength = 0.1, kGap = 1e-4;

struct Cylinders {
  nurbs::NurbsSurface a = nurbs::MakeCylinder(kRadius, kLength);
  nurbs::NurbsSurface b = nurbs::MakeCylinder(kRadius, kLength);
  std::unique_ptr<optimizer::Problem> problem;
  std::unique_ptr<optimizer::Solver> solver;
  LineContacts lines;
  std::vector<contact::BodyPose> poses;
  // b beside a along x, its axis turned by `angle` about x (0: parallel, π/2: crossing).
  explicit Cylinders(double angle) {
    optimizer::Mechanism m;
    m.AddBody(optimizer::Body{"a"});
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()));
    const Eigen::Vector3d mid(2 * kRadius + kGap, 0, kLength / 2);
    optimizer::Body body_b{"b"};
    body_b.fixed = true;
    m.AddBody(body_b);
    problem = std::make_unique<optimizer::Problem>(m);
    lines.AddPair(problem.get(), 0, &a, 1, &this->b);
    solver = std::make_unique<optimizer::Solver>(*problem);
    lines.Bind(solver.get());
    Eigen::VectorXd q = problem->mechanism().InitialCoordinates();
    problem->mechanism().Poses(q, &poses);
    contact::Vector7d qb;
    qb << mid - turn * Eigen::Vector3d(0, 0, kLength / 2), turn.w(), turn.x(), turn.y(), turn.z();
    poses[1] = contact::BodyPose::FromCoordinates(qb);
  }
  // The pair's extremum near the middle of both, and the sections after one follow.
  contact::SurfaceSurfaceExtremum Follow(contact::SurfacePairEval* e) {
    const contact::SurfaceSurfaceExtremum x = contact::SolveSurfaceSurface(
        a, poses[0], b, poses[1], Eigen::Vector4d(0.0, 0.5, 0.5, 0.5), contact::kContinuation, e);
    lines.BeginPair(0);
    lines.Consider(0, x, *e);
    lines.EndPair(0);
    return x;
  }
  double SectionGap(int side) {
    auto& st = const_cast<optimizer::SectionContactTerm::State&>(lines.section(0, side));
    const auto& term = static_cast<const optimizer::SectionContactTerm&>(
        *problem->inequalities()[static_cast<size_t>(side)].term);
    term.Update(poses, &st);
    return st.ext.beta;
  }
};

TEST(LineContactsTest, SideBySideCylindersAreHeldAtTwoSectionsAcrossTheLine) {
  // 0.01 rad from parallel (exactly parallel the pair's extremum is a line of minima, and its
  // solve does not converge: the case the sections are for).
  Cylinders c(0.01);
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Follow(&e);
  ASSERT_EQ(x.status, contact::ExtremalStatus::kConverged);
  EXPECT_NEAR(x.beta, kGap, 1e-12);
  ASSERT_TRUE(c.lines.line(0));
  const auto& lo = c.lines.section(0, 0);
  const auto& hi = c.lines.section(0, 1);
  EXPECT_EQ(lo.fixed, 1);  // the line runs along v (the axis): the sections hold v, round u
  EXPECT_EQ(hi.fixed, 1);
  EXPECT_LT((lo.value - x.u[1]) * (hi.value - x.u[1]), 0.0) << "one either side";
  for (int side = 0; side < 2; ++side) {
    // Beside the contact the gap opens by ½ λ_min h² (λ_min ≈ θ²/r for cylinders turned by θ).
    EXPECT_GE(c.SectionGap(side), x.beta - 1e-15) << side;
    EXPECT_NEAR(c.SectionGap(side), x.beta, 1e-6) << side;
    EXPECT_EQ(c.lines.section(0, side).ext.kind, contact::ExtremumKind::kMinimum);
  }
}

TEST(LineContactsTest, CrossingCylindersStayOnePoint) {
  Cylinders c(M_PI / 2);
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Follow(&e);
  ASSERT_EQ(x.status, contact::ExtremalStatus::kConverged);
  EXPECT_FALSE(c.lines.line(0));
  EXPECT_FALSE(c.lines.section(0, 0).active);
  EXPECT_EQ(c.lines.placements(), 0);
}

TEST(LineContactsTest, PlacedBelowEnterAndTakenAwayAboveLeave) {
  // Crossing at angle θ: the relative curvature's eigenvalue ratio grows with θ. Find angles
  // either side of enter (0.1) and leave (0.25) and step through them.
  auto ratio_at = [](double angle) {
    Cylinders c(angle);
    contact::SurfacePairEval e;
    c.Follow(&e);
    const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(e);
    return rc.eigenvalues[0] / rc.eigenvalues[1];
  };
  double between = 0.0, above = 0.0;
  for (double t = 0.01; t < 1.5; t += 0.01) {
    const double r = ratio_at(t);
    if (between == 0.0 && r > 0.12 && r < 0.23) between = t;
    if (above == 0.0 && r > 0.3) above = t;
  }
  ASSERT_GT(between, 0.0);
  ASSERT_GT(above, between);
  {
    Cylinders c(between);  // between the thresholds from a point contact: stays one point
    contact::SurfacePairEval e;
    c.Follow(&e);
    EXPECT_FALSE(c.lines.line(0));
  }
  Cylinders c(0.01);
  contact::SurfacePairEval e;
  c.Follow(&e);
  ASSERT_TRUE(c.lines.line(0));
  Cylinders turned(between);  // the same surfaces turned: the line is kept (hysteresis) ...
  c.poses = turned.poses;
  c.Follow(&e);
  EXPECT_TRUE(c.lines.line(0));
  Cylinders crossing(above);  // ... until the ratio passes leave
  c.poses = crossing.poses;
  c.Follow(&e);
  EXPECT_FALSE(c.lines.line(0));
}

TEST(LineContactsTest, FollowingAllocatesNothing) {
  Cylinders c(0.01);
  contact::SurfacePairEval e;
  c.Follow(&e);
  const contact::SurfaceSurfaceExtremum x =
      contact::SolveSurfaceSurface(c.a, c.poses[0], c.b, c.poses[1],
                                   Eigen::Vector4d(0.0, 0.5, 0.5, 0.5), contact::kContinuation, &e);
  const long before = testing::AllocationCount();
  for (int k = 0; k < 100; ++k) {
    c.lines.BeginPair(0);
    c.lines.Consider(0, x, e);
    c.lines.EndPair(0);
    c.lines.Clear();
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_EQ(c.lines.placements(), 100);  // the first loop finds the sections placed already
}

}  // namespace
}  // namespace tangent::server
