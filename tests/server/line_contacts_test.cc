// The servo's line contacts (server/line_contacts.h) on two cylinders nearly side by side (a line
// contact: relative curvature nearly zero along the axes): line mode with three sections across
// the line, the middle one at the contact's distance and the sides a little farther; crossing
// cylinders (a point contact) stay one point; the line is left when it turns to crossing and
// released when the cylinders part; a contact along the line is the line's; and following a
// line allocates nothing.

#include "server/line_contacts.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

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
  explicit Cylinders(const LineContactOptions& options = {}) : lines(options) {
    optimizer::Mechanism m;
    m.AddBody(optimizer::Body{"a"});
    optimizer::Body body_b{"b"};
    body_b.fixed = true;
    m.AddBody(body_b);
    problem = std::make_unique<optimizer::Problem>(m);
    lines.AddPair(problem.get(), 0, &a, 1, &b);
    solver = std::make_unique<optimizer::Solver>(*problem);
    lines.Bind(solver.get());
    problem->mechanism().Poses(problem->mechanism().InitialCoordinates(), &poses);
    Turn(0.01, kGap);
  }
  // b beside a along x at `gap`, its axis turned by `angle` about x (0: parallel, π/2: crossing),
  // and moved by `along` along a's axis (the skew axes' nearest points move with it).
  void Turn(double angle, double gap, double along = 0.0) {
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()));
    const Eigen::Vector3d mid(2 * kRadius + gap, 0, kLength / 2 + along);
    contact::Vector7d qb;
    qb << mid - turn * Eigen::Vector3d(0, 0, kLength / 2), turn.w(), turn.x(), turn.y(), turn.z();
    poses[1] = contact::BodyPose::FromCoordinates(qb);
  }
  // The pair's extremum near the middle of both.
  contact::SurfaceSurfaceExtremum Pair(contact::SurfacePairEval* e) const {
    return contact::SolveSurfaceSurface(
        a, poses[0], b, poses[1], Eigen::Vector4d(0.0, 0.5, 0.5, 0.5), contact::kContinuation, e);
  }
  // The least of the sections' distances, and the world distance between the middle section's
  // point on a and the +1 section's.
  double LeastSection() const {
    double least = INFINITY;
    for (int i = 0; i < LineContacts::kSections; ++i) {
      least = std::min(least, lines.section(0, i).ext.beta);
    }
    return least;
  }
  double Spacing() const {
    return (lines.section(0, 2).ext.p_f - lines.section(0, 0).ext.p_f).norm();
  }
  // The sections evaluated at the poses (as the servo's solve leaves them).
  void Measure() {
    for (int i = 0; i < LineContacts::kSections; ++i) {
      const auto& term = static_cast<const optimizer::SectionContactTerm&>(
          *problem->inequalities()[static_cast<size_t>(i)].term);
      term.Update(poses, &const_cast<optimizer::SectionContactTerm::State&>(lines.section(0, i)));
    }
  }
};

TEST(LineContactsTest, ALineLikeContactIsHeldByThreeSectionsAcrossTheLine) {
  Cylinders c;
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Pair(&e);
  ASSERT_EQ(x.status, contact::ExtremalStatus::kConverged);
  EXPECT_NEAR(x.beta, kGap, 1e-12);
  ASSERT_TRUE(c.lines.Enter(0, x, e));
  ASSERT_TRUE(c.lines.line(0));
  c.Measure();
  const auto& mid = c.lines.section(0, 0);
  const auto& lo = c.lines.section(0, 1);
  const auto& hi = c.lines.section(0, 2);
  EXPECT_EQ(mid.fixed, 1);  // the line runs along v (the axis): the sections hold v, round u
  EXPECT_NEAR(mid.value, x.u[1], 1e-15);
  EXPECT_LT((lo.value - x.u[1]) * (hi.value - x.u[1]), 0.0) << "one either side";
  EXPECT_NEAR(mid.ext.beta, x.beta, 1e-12);
  for (int i = 0; i < LineContacts::kSections; ++i) {
    const auto& s = c.lines.section(0, i);
    EXPECT_EQ(s.ext.kind, contact::ExtremumKind::kMinimum) << i;
    // Off the contact along the line the gap opens by ½ λ_min δ² (λ_min ≈ θ²/r here).
    EXPECT_GE(s.ext.beta, x.beta - 1e-15) << i;
    EXPECT_NEAR(s.ext.beta, x.beta, 1e-6) << i;
  }
  EXPECT_TRUE(c.lines.Covers(0, x.u));
  Eigen::Vector4d far = x.u;
  far[1] += 0.4;
  EXPECT_FALSE(c.lines.Covers(0, far));
  const Eigen::Vector4d m = c.lines.MiddleU(0);
  EXPECT_LT((m - x.u).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(LineContactsTest, ACrossingContactStaysOnePoint) {
  Cylinders c;
  c.Turn(M_PI / 2, kGap);
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Pair(&e);
  ASSERT_EQ(x.status, contact::ExtremalStatus::kConverged);
  EXPECT_FALSE(c.lines.Enter(0, x, e));
  EXPECT_FALSE(c.lines.line(0));
  EXPECT_FALSE(c.lines.section(0, 0).active);
  EXPECT_EQ(c.lines.placements(), 0);
}

// The relative curvature's eigenvalue ratio of the cylinders turned by `angle`.
double RatioAt(double angle) {
  Cylinders c;
  c.Turn(angle, kGap);
  contact::SurfacePairEval e;
  c.Pair(&e);
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(e);
  return rc.eigenvalues[0] / rc.eigenvalues[1];
}

TEST(LineContactsTest, LeftWithHysteresisWhenTheLineTurnsToCrossing) {
  double between = 0.0, above = 0.0;  // ratios within (enter, leave) and above leave
  for (double t = 0.01; t < 1.5 && above == 0.0; t += 0.01) {
    const double r = RatioAt(t);
    if (between == 0.0 && r > 0.12 && r < 0.23) between = t;
    if (r > 0.3) above = t;
  }
  ASSERT_GT(between, 0.0);
  ASSERT_GT(above, between);
  Cylinders c;
  contact::SurfacePairEval e;
  ASSERT_TRUE(c.lines.Enter(0, c.Pair(&e), e));
  Eigen::Vector4d u;
  c.Turn(between, kGap);  // not line-like enough to enter, still enough to stay
  c.Measure();
  EXPECT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kStay);
  EXPECT_TRUE(c.lines.line(0));
  c.Turn(above, kGap);
  c.Measure();
  EXPECT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kLeave);
  EXPECT_FALSE(c.lines.line(0));
  EXPECT_FALSE(c.lines.section(0, 1).active);
  // The point resumes at the middle section: the pair's extremum from there is the contact.
  const contact::SurfaceSurfaceExtremum back =
      contact::SolveSurfaceSurface(c.a, c.poses[0], c.b, c.poses[1], u, contact::kContinuation);
  EXPECT_EQ(back.status, contact::ExtremalStatus::kConverged);
  EXPECT_NEAR(back.beta, kGap, 1e-9);
}

TEST(LineContactsTest, ReleasedWhenThePartsPart) {
  Cylinders c;
  contact::SurfacePairEval e;
  ASSERT_TRUE(c.lines.Enter(0, c.Pair(&e), e));
  Eigen::Vector4d u;
  c.Turn(0.01, 0.05);  // 5 cm apart: farther than the sections' spacing
  c.Measure();
  EXPECT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kRelease);
  EXPECT_FALSE(c.lines.line(0));
}

TEST(LineContactsTest, SectionDipIsTheParabolasLowestPointBetweenTheSections) {
  // Sections at −1, 0, 1 on d(x) = a (x − x₀)² + b: the dip is at x₀ whenever x₀ lies strictly
  // between the outer two and off the sections.
  for (double x0 : {-0.9, -0.45, -0.1, 0.3, 0.7}) {
    auto d = [&](double x) { return 2e-6 * (x - x0) * (x - x0) + 1e-4; };
    double at = 0.0;
    ASSERT_TRUE(SectionDip(d(-1), d(0), d(1), &at)) << x0;
    EXPECT_NEAR(at, x0, 1e-9) << x0;
  }
  double at = 0.0;
  auto at_x0 = [&](double x0, double a) {
    auto d = [&](double x) { return a * (x - x0) * (x - x0); };
    return SectionDip(d(-1), d(0), d(1), &at);
  };
  EXPECT_FALSE(at_x0(0.0, 1.0)) << "the lowest point on a section: no dip";
  EXPECT_FALSE(at_x0(1.5, 1.0)) << "beside the sections";
  EXPECT_FALSE(at_x0(-1.0, 1.0)) << "on an outer section";
  EXPECT_FALSE(at_x0(0.3, -1.0)) << "concave";
  EXPECT_FALSE(SectionDip(1e-4, 1e-4, 1e-4, &at)) << "a straight line of minima";
  EXPECT_FALSE(SectionDip(INFINITY, 1e-4, 2e-4, &at)) << "a section that did not solve";
  EXPECT_FALSE(SectionDip(NAN, 1e-4, 2e-4, &at));
}

// The section spacing when the cylinders are turned by `angle` and the pair enters line mode
// there; the gap's dip below the sections when b then moves `along` spacings along the line.
struct Spaced {
  double spacing = 0.0, dip = 0.0;
};
Spaced SpacedAt(Cylinders* c, double angle, double along) {
  Spaced r;
  c->Turn(angle, kGap);
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c->Pair(&e);
  EXPECT_EQ(x.status, contact::ExtremalStatus::kConverged);
  EXPECT_TRUE(c->lines.Enter(0, x, e)) << angle;
  c->Measure();
  r.spacing = c->Spacing();
  c->Turn(angle, kGap, along * r.spacing);
  c->Measure();
  r.dip = c->LeastSection() - kGap;  // (kGap: the skew axes' nearest points, wherever they are)
  return r;
}

TEST(LineContactsTest, TheSectionsAreSpacedSoTheGapDipsAtMostTheDipBetweenThem) {
  // Along the line the gap is β + ½ λ_min δ²: with the minimum midway between two sections they
  // read it high by ½ λ_min (h/2)². The spacing keeps that within LineContactOptions::dip, and
  // the bound is what sets it here (the tight direction's 1/λ_max is 5 mm).
  for (double angle : {0.1, 0.2, 0.3}) {
    Cylinders c;
    const Spaced s = SpacedAt(&c, angle, 0.5);
    const double dip = LineContactOptions{}.dip;
    std::printf("turned %.1f rad: spacing %.3e m, the gap %.3e m below the sections midway\n",
                angle, s.spacing, s.dip);
    EXPECT_LT(s.spacing, 0.5 / (2.0 / kRadius)) << angle;
    EXPECT_LE(s.dip, dip) << angle;
    EXPECT_GT(s.dip, 0.8 * dip) << angle << ": the bound, not looser";
  }
  // Without the bound (dip 0: the tight direction's length scale alone) the same line lets the
  // gap dip a hundred times deeper between the sections.
  LineContactOptions loose;
  loose.dip = 0.0;
  Cylinders c(loose);
  EXPECT_GT(SpacedAt(&c, 0.3, 0.5).dip, 100 * LineContactOptions{}.dip);
  EXPECT_NEAR(LineSpacing(4.0, 100.0, 1e-7), 2.0 * std::sqrt(2.0 * 1e-7 / 4.0), 1e-18);
  EXPECT_EQ(LineSpacing(-4.0, 100.0, 1e-7), 0.01);  // past the pitchfork: 1/λ_max
  EXPECT_EQ(LineSpacing(4.0, 100.0, 0.0), 0.01);
  EXPECT_EQ(LineSpacing(0.0, 0.0, 1e-7), INFINITY);
}

TEST(LineContactsTest, ALineWhoseCurvatureGrowsBringsItsSectionsCloser) {
  // Entered nearly parallel (λ_min tiny: spaced by 1/λ_max), then turned to 0.3 rad, still a
  // line (λ_min below leave · λ_max): the sections, 5 mm apart, would let the gap dip 1e-5 m
  // between them; after the next good tick they are brought closer about the middle.
  Cylinders c;
  const Spaced wide = SpacedAt(&c, 0.01, 0.0);
  ASSERT_GT(RatioAt(0.3), 0.0);
  ASSERT_LT(RatioAt(0.3), LineContactOptions{}.leave);
  c.Turn(0.3, kGap);
  c.Measure();
  Eigen::Vector4d u;
  const long before = testing::AllocationCount();
  ASSERT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kStay);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_EQ(c.lines.respaced(), 1);
  c.Measure();
  const double spacing = c.Spacing();
  std::printf("spacing %.3e m entered, %.3e m at 0.3 rad\n", wide.spacing, spacing);
  EXPECT_LT(spacing, 0.1 * wide.spacing);
  // Midway between two of them the gap now dips about the dip below them (to 5 %: the spacing
  // is mapped into f's parameter at the rate measured at entry, here 1 % off at 0.3 rad).
  c.Turn(0.3, kGap, 0.5 * spacing);
  c.Measure();
  EXPECT_LE(c.LeastSection() - kGap, 1.05 * LineContactOptions{}.dip);
  // Another good tick at the same curvature leaves them where they are.
  ASSERT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kStay);
  EXPECT_EQ(c.lines.respaced(), 1);
}

TEST(LineContactsTest, TheSectionsHoldTheGapWhereItDipsBetweenThem) {
  // Two cylinders 0.3 rad from parallel: the gap along the line is least where the skew axes
  // are nearest. Moved along the axis so that this lies between two sections, the sections read
  // more than the gap; the margin they then hold is how much more, measured at the dip. (Spaced
  // by 1/λ_max alone, dip 0, so that they straddle a dip worth measuring; spaced by the dip
  // bound the margin holds what a line's curvature does that the bound did not foresee.)
  LineContactOptions loose;
  loose.dip = 0.0;
  Cylinders c(loose);
  c.Turn(0.3, kGap);
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Pair(&e);
  ASSERT_EQ(x.status, contact::ExtremalStatus::kConverged);
  ASSERT_TRUE(c.lines.Enter(0, x, e));
  c.Measure();
  const double spacing = c.Spacing();
  ASSERT_GT(spacing, 1e-3);
  Eigen::Vector4d u;
  for (double along : {0.3, 0.55, -0.4}) {
    c.Turn(0.3, kGap, along * spacing);
    c.Measure();
    const double least = c.LeastSection();
    ASSERT_GT(least - kGap, 1e-7) << along << ": the sections straddle the dip";
    const long before = testing::AllocationCount();
    ASSERT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kStay);
    EXPECT_EQ(testing::AllocationCount() - before, 0);
    std::printf("moved %.2f spacings: sections %.3e m above the gap, margin %.3e m\n", along,
                least - kGap, c.lines.section(0, 0).margin);
    for (int i = 0; i < LineContacts::kSections; ++i) {
      // (The skew axes' gap is a hyperbola along the line, not a parabola: the probe at the
      // parabola's lowest point is off the true one by a little, and reads second order high.)
      EXPECT_NEAR(c.lines.section(0, i).margin, least - kGap, 2e-3 * (least - kGap)) << along;
    }
  }
  // Parallel again (a straight line of minima): no dip, no margin.
  c.Turn(0.0, kGap);
  c.Measure();
  ASSERT_EQ(c.lines.Follow(0, c.poses, &u), LineContacts::Next::kStay);
  EXPECT_EQ(c.lines.section(0, 0).margin, 0.0);
}

TEST(LineContactsTest, FollowingAllocatesNothing) {
  Cylinders c;
  contact::SurfacePairEval e;
  const contact::SurfaceSurfaceExtremum x = c.Pair(&e);
  Eigen::Vector4d u;
  const long before = testing::AllocationCount();
  for (int k = 0; k < 100; ++k) {
    c.lines.Enter(0, x, e);
    c.Measure();
    c.lines.Follow(0, c.poses, &u);
    c.lines.Leave(0, &u);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_EQ(c.lines.placements(), 100);
}

}  // namespace
}  // namespace tangent::server
