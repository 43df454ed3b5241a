// Relative curvature of a contact pair (contact/relative_curvature.h): the shape operator
// against Meusnier finite differences on a non-orthogonal rational patch and a torus; the
// relative curvature of analytic pairs (spheres, crossed and parallel cylinders, linked tori
// loose and tight); the second-order gap it predicts against re-solved point–surface distances;
// the extremal solver calling a touching saddle a saddle; and the global stage splitting a
// tracked saddle into the minima either side of it, and merging two contacts on one point.

#include "contact/relative_curvature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "contact/global.h"
#include "nurbs/offset.h"
#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

constexpr double mm = 1e-3;

Vector7d Pose(const Eigen::Vector3d& p,
              const Eigen::Quaterniond& Q = Eigen::Quaterniond::Identity()) {
  Vector7d q;
  q << p, Q.w(), Q.x(), Q.y(), Q.z();
  return q;
}

// The extremal pair of f and g nearest a sampled seed, and the pair's evaluation there.
SurfaceSurfaceExtremum Touch(const nurbs::NurbsSurface& f, const BodyPose& pf,
                             const nurbs::NurbsSurface& g, const BodyPose& pg,
                             SurfacePairEval* at) {
  double distance = 0.0;
  const Eigen::Vector4d seed = ClosestSamplePair(f, pf, g, pg, 24, &distance);
  return SolveSurfaceSurface(f, pf, g, pg, seed, {}, at);
}

// tᵀ K t against Meusnier's theorem by central differences: the curve c(s) = S(u + s a) with
// a = I⁻¹Tᵀt has c'(0) = t (unit) and normal curvature c''·n, K's sign convex-positive (−c''·n).
// Steps of 1e-4 and 5e-5 m of arc, Richardson-extrapolated: truncation ~h⁴ |S⁽⁶⁾| and rounding
// ~eps |S| / h² ≈ 1e-8 of the curvature; 1e-6 of the largest leaves room for both.
TEST(ShapeOperatorTest, MatchesMeusnierFiniteDifferencesOnNonOrthogonalAndRationalSurfaces) {
  const nurbs::NurbsSurface sheared =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, 0.01, /*rational=*/true);
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.04, 0.01);
  const BodyPose pose = BodyPose::FromCoordinates(
      Pose(Eigen::Vector3d(0.1, -0.2, 0.3),
           Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()))));
  for (const nurbs::NurbsSurface* surface : {&sheared, &torus}) {
    for (const auto& [u, v] : {std::pair{0.31, 0.47}, {0.72, 0.18}, {0.55, 0.9}}) {
      nurbs::SpanHint hint;
      PlacedSurfacePoint p;
      EvaluatePlaced(*surface, pose, u, v, &hint, &p);
      Eigen::Matrix3d K;
      ASSERT_TRUE(ShapeOperator(p, &K));
      const Eigen::Vector3d n = p.N_W.normalized();
      Eigen::Matrix<double, 3, 2> T;
      T << p.world.S_u, p.world.S_v;
      const Eigen::Vector3d e1 = p.world.S_u.normalized(), e2 = n.cross(e1);
      double scale = 0.0;
      for (int k = 0; k < 3; ++k) scale = std::max(scale, K.col(k).norm());
      for (double theta = 0.0; theta < std::numbers::pi; theta += std::numbers::pi / 5) {
        const Eigen::Vector3d t = std::cos(theta) * e1 + std::sin(theta) * e2;
        const Eigen::Vector2d a = (T.transpose() * T).inverse() * (T.transpose() * t);
        auto second = [&](double h) {  // c'' by central differences with step h (m of arc)
          auto at = [&](double s) {
            return pose.Point(surface->Evaluate(u + s * h * a[0], v + s * h * a[1], 0).S);
          };
          return Eigen::Vector3d((at(1.0) - 2.0 * at(0.0) + at(-1.0)) / (h * h));
        };
        // Richardson: the h² truncation cancels, leaving h⁴.
        const Eigen::Vector3d c2 = (4.0 * second(0.5e-4) - second(1e-4)) / 3.0;
        EXPECT_NEAR(t.dot(K * t), -c2.dot(n), 1e-6 * scale) << "theta " << theta;
      }
      // Symmetric, and zero along the normal.
      EXPECT_LT((K - K.transpose()).norm(), 1e-12 * scale);
      EXPECT_LT((K * n).norm(), 1e-12 * scale);
    }
  }
}

TEST(ShapeOperatorTest, UndefinedAtAPole) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.02);
  nurbs::SpanHint hint;
  PlacedSurfacePoint p;
  EvaluatePlaced(sphere, BodyPose::FromCoordinates(Pose(Eigen::Vector3d::Zero())), 0.3, 0.0, &hint,
                 &p);
  Eigen::Matrix3d K;
  EXPECT_FALSE(ShapeOperator(p, &K));
  EXPECT_EQ(K, Eigen::Matrix3d::Zero());
}

// Named configurations with their relative curvatures in closed form (1/m), each in two world
// placements (frame invariance).
TEST(RelativeCurvatureTest, AnalyticPairs) {
  const double R1 = 0.02, R2 = 0.035, r = 0.01;
  const nurbs::NurbsSurface s1 = nurbs::MakeSphere(Eigen::Vector3d::Zero(), R1);
  const nurbs::NurbsSurface s2 = nurbs::MakeSphere(Eigen::Vector3d::Zero(), R2);
  const nurbs::NurbsSurface c1 = nurbs::MakeCylinder(r, 0.1);
  const nurbs::NurbsSurface c2 = nurbs::MakeCylinder(1.5 * r, 0.1);
  const Eigen::Quaterniond about_x(
      Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  struct Case {
    const char* name;
    const nurbs::NurbsSurface *f, *g;
    Vector7d q_f, q_g;
    Eigen::Vector2d eigenvalues;
    bool crossing;
  };
  const std::vector<Case> cases = {
      {"spheres", &s1, &s2, Pose(Eigen::Vector3d::Zero()), Pose(Eigen::Vector3d(R1 + R2, 0, 0)),
       Eigen::Vector2d(1 / R1 + 1 / R2, 1 / R1 + 1 / R2), false},
      // Axes z and y, apart along x: curvature 1/r across each, none along each axis.
      {"crossed cylinders", &c1, &c2, Pose(Eigen::Vector3d(0, 0, -0.05)),
       Pose(Eigen::Vector3d(2.5 * r, -0.05, 0), about_x.inverse()),
       Eigen::Vector2d(1 / (1.5 * r), 1 / r), false},
      // Parallel axes: a line contact, M singular but not indefinite.
      {"parallel cylinders", &c1, &c2, Pose(Eigen::Vector3d(0, 0, -0.05)),
       Pose(Eigen::Vector3d(2.5 * r, 0, -0.05)), Eigen::Vector2d(0, 1 / r + 1 / (1.5 * r)), false},
  };
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 3, 2).normalized()));
  for (const Case& c : cases) {
    for (int placement = 0; placement < 2; ++placement) {
      auto place = [&](const Vector7d& q) {
        if (placement == 0) return BodyPose::FromCoordinates(q);
        const Eigen::Quaterniond Q(q[3], q[4], q[5], q[6]);
        return BodyPose::FromCoordinates(
            Pose(turn * Eigen::Vector3d(q.head<3>()) + Eigen::Vector3d(0.3, -0.1, 0.2), turn * Q));
      };
      SurfacePairEval at;
      const SurfaceSurfaceExtremum e = Touch(*c.f, place(c.q_f), *c.g, place(c.q_g), &at);
      ASSERT_EQ(e.status, ExtremalStatus::kConverged) << c.name;
      ASSERT_NEAR(e.beta, 0.0, 1e-12) << c.name;
      const RelativeCurvature k = RelativeCurvatureOf(at);
      ASSERT_TRUE(k.valid) << c.name;
      EXPECT_NEAR(k.eigenvalues[0], c.eigenvalues[0], 1e-7 * c.eigenvalues[1]) << c.name;
      EXPECT_NEAR(k.eigenvalues[1], c.eigenvalues[1], 1e-7 * c.eigenvalues[1]) << c.name;
      EXPECT_EQ(k.crossing, c.crossing) << c.name;
      EXPECT_EQ(e.kind, ExtremumKind::kMinimum) << c.name;
    }
  }
}

// Two linked tori touching at their inner equators (the paperclip hook): torus 1 (R1, r1) in
// the xy plane, torus 2 (R2, r2) in the xz plane through its hole. At the contact the tangent
// directions are y and z: M = diag(1/r2 − 1/(R1 − r1), 1/r1 − 1/(R2 − r2)). A wire thicker
// than the hole it passes through (r2 > R1 − r1) makes the first negative: a saddle, the wire
// crossing the hole's wall on either side along y.
// With `turn` ≠ 0, torus 2 is turned further about the contact normal (the x axis, through both
// centres): the wires cross at 90° − turn, and M = A + R B Rᵀ with A = diag(−1/(R1 − r1), 1/r1),
// B = diag(1/r2, −1/(R2 − r2)) in (y, z) and R the turn. Equal tori turned past the angle where
// det M = 0 form the pitchfork the paperclip chain reaches: the contact becomes a saddle, with
// two shallow minima either side of it.
struct LinkedTori {
  double R1, r1, R2, r2, turn = 0.0;
  nurbs::NurbsSurface t1 = nurbs::MakeTorus(R1, r1), t2 = nurbs::MakeTorus(R2, r2);
  BodyPose p1 = BodyPose::FromCoordinates(Pose(Eigen::Vector3d::Zero()));
  BodyPose p2 =
      BodyPose::FromCoordinates(Pose(Eigen::Vector3d(R1 - r1 + R2 - r2, 0, 0),
                                     Eigen::Quaterniond(Eigen::AngleAxisd(
                                         std::numbers::pi / 2 + turn, Eigen::Vector3d::UnitX()))));
  // The contact pair: the inner equators, found from the sampled seed nearest (R1 − r1, 0, 0).
  SurfaceSurfaceExtremum Contact(SurfacePairEval* at) const {
    // u = 0 is the +x meridian of each torus; the inner equator is half way round the tube.
    for (double v1 : {0.0, 0.25, 0.5, 0.75}) {
      for (double v2 : {0.0, 0.25, 0.5, 0.75}) {
        const SurfaceSurfaceExtremum e =
            SolveSurfaceSurface(t1, p1, t2, p2, Eigen::Vector4d(0.0, v1, 0.5, v2), {}, at);
        if (e.status == ExtremalStatus::kConverged && std::abs(e.beta) < 1e-12 &&
            (e.p_f - Eigen::Vector3d(R1 - r1, 0, 0)).norm() < 1e-9) {
          return e;
        }
      }
    }
    ADD_FAILURE() << "no touching pair at the inner equators";
    return {};
  }
};

TEST(RelativeCurvatureTest, LinkedToriLooseAndTight) {
  for (const bool tight : {false, true}) {
    const LinkedTori L = tight ? LinkedTori{1.0 * mm, 0.4 * mm, 2.0 * mm, 0.8 * mm}
                               : LinkedTori{2.0 * mm, 0.4 * mm, 2.0 * mm, 0.8 * mm};
    SurfacePairEval at;
    const SurfaceSurfaceExtremum e = L.Contact(&at);
    const RelativeCurvature k = RelativeCurvatureOf(at);
    ASSERT_TRUE(k.valid);
    const double along_y = 1 / L.r2 - 1 / (L.R1 - L.r1), along_z = 1 / L.r1 - 1 / (L.R2 - L.r2);
    EXPECT_NEAR(k.eigenvalues[0], std::min(along_y, along_z), 1e-7 * along_z);
    EXPECT_NEAR(k.eigenvalues[1], std::max(along_y, along_z), 1e-7 * along_z);
    EXPECT_EQ(k.crossing, tight);
    EXPECT_EQ(e.kind, tight ? ExtremumKind::kSaddle : ExtremumKind::kMinimum);
    if (tight) {
      EXPECT_NEAR(std::abs(k.min_direction.y()), 1.0, 1e-9);
    }
  }
}

TEST(RelativeCurvatureTest, LinkedToriTurnedAboutTheNormal) {
  for (const double degrees : {0.0, 10.0, 20.0, 35.0}) {
    const double turn = degrees * std::numbers::pi / 180;
    const LinkedTori L{1.2 * mm, 0.45 * mm, 1.2 * mm, 0.45 * mm, turn};
    SurfacePairEval at;
    const SurfaceSurfaceExtremum e = L.Contact(&at);
    const RelativeCurvature k = RelativeCurvatureOf(at);
    ASSERT_TRUE(k.valid);
    const Eigen::Matrix2d A = Eigen::Vector2d(-1 / (L.R1 - L.r1), 1 / L.r1).asDiagonal();
    const Eigen::Matrix2d B = Eigen::Vector2d(1 / L.r2, -1 / (L.R2 - L.r2)).asDiagonal();
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(turn).toRotationMatrix();
    const Eigen::Vector2d expected =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(A + R * B * R.transpose()).eigenvalues();
    EXPECT_NEAR(k.eigenvalues[0], expected[0], 1e-7 * expected[1]) << degrees;
    EXPECT_NEAR(k.eigenvalues[1], expected[1], 1e-7 * expected[1]) << degrees;
    EXPECT_EQ(k.crossing, expected[0] < 0.0) << degrees;
    EXPECT_EQ(e.kind, expected[0] < 0.0 ? ExtremumKind::kSaddle : ExtremumKind::kMinimum);
  }
}

// The gap M predicts, against the re-solved signed distance of f's points at a tangent offset ξ
// from g: ½ λ ξ² along each eigenvector, to O(ξ³) (ξ = 1 % of the curvature radius: 1e-2
// relative).
TEST(RelativeCurvatureTest, PredictsTheGapToSecondOrder) {
  const LinkedTori L{1.0 * mm, 0.4 * mm, 2.0 * mm, 0.8 * mm};
  SurfacePairEval at;
  const SurfaceSurfaceExtremum e = L.Contact(&at);
  const RelativeCurvature k = RelativeCurvatureOf(at);
  const Eigen::Vector3d n = at.g.N_W.normalized();
  const Eigen::Vector3d w_max = n.cross(k.min_direction);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d w = i == 0 ? k.min_direction : w_max;
    const double xi = 1e-2 / k.eigenvalues.cwiseAbs().maxCoeff();
    for (const double side : {1.0, -1.0}) {
      const Eigen::Vector4d step = ParameterStepAlong(at, side * xi * w);
      // (u wraps: the contact sits on torus 1's seam, u = 0 ≡ 1.)
      const double u1 = std::fmod(e.u[0] + step[0] + 1.0, 1.0), v1 = e.u[1] + step[1];
      const Eigen::Vector3d x = L.p1.Point(L.t1.Evaluate(u1, v1, 0).S);
      const PointSurfaceExtremum d =
          SolvePointSurface(x, L.t2, L.p2, e.u.tail<2>() + step.tail<2>());
      ASSERT_EQ(d.status, ExtremalStatus::kConverged);
      const double predicted = 0.5 * k.eigenvalues[i] * xi * xi;
      EXPECT_NEAR(d.distance, predicted, 1e-2 * std::abs(predicted)) << "eigenvector " << i;
    }
  }
}

struct StageFixture {
  LinkedTori L{1.2 * mm, 0.45 * mm, 1.2 * mm, 0.45 * mm, 20 * std::numbers::pi / 180};
  nurbs::OffsetMesh m1 = nurbs::MakeOffsetMesh(L.t1, 20e-6, 0.25e-3, 0.5e-3);
  nurbs::OffsetMesh m2 = nurbs::MakeOffsetMesh(L.t2, 20e-6, 0.25e-3, 0.5e-3);
  GlobalContactStage stage{std::vector<GlobalSurface>{{0, &L.t1, &m1}, {1, &L.t2, &m2}},
                           std::vector<std::pair<int, int>>{{0, 1}}, GlobalOptions{}};
  std::vector<BodyPose> poses{L.p1, L.p2};
};

// A tracked contact at the tight saddle: removed as split, and the two minima either side of it
// along the crossing direction added (each a minimum, interpenetrating by the saddle's dip).
TEST(ContactSplitTest, AStageSplitsATrackedSaddleIntoTheMinimaEitherSide) {
  StageFixture s;
  SurfacePairEval at;
  const SurfaceSurfaceExtremum e = s.L.Contact(&at);
  const RelativeCurvature k = RelativeCurvatureOf(at);
  ASSERT_TRUE(k.crossing);
  const std::vector<GlobalContact> tracked = {{0, 1, e.u, e.beta, e.p_f, e.p_g}};
  std::vector<ContactEvent> events;
  s.stage.Run(s.poses, tracked, &events);
  int removed = 0, added = 0;
  double sides = 0.0;
  for (const ContactEvent& ev : events) {
    EXPECT_EQ(ev.reason, ContactEvent::Reason::kSplit) << ToString(ev.reason);
    if (ev.kind == ContactEvent::Kind::kRemoved) {
      ++removed;
      EXPECT_EQ(ev.contact.u, e.u);
      continue;
    }
    ++added;
    const Eigen::Vector3d moved = ev.contact.p_b - e.p_g;
    EXPECT_GT(std::abs(moved.dot(k.min_direction)), 0.05 * mm);
    sides += moved.dot(k.min_direction) > 0 ? 1.0 : -1.0;
    EXPECT_LT(ev.contact.beta, 0.0);
    SurfacePairEval q;
    nurbs::SpanHint h1, h2;
    EvaluatePair(s.L.t1, s.L.p1, s.L.t2, s.L.p2, ev.contact.u, &h1, &h2, &q);
    const RelativeCurvature kq = RelativeCurvatureOf(q);
    EXPECT_TRUE(kq.valid && !kq.crossing);
    const SurfaceSurfaceExtremum again =
        SolveSurfaceSurface(s.L.t1, s.L.p1, s.L.t2, s.L.p2, ev.contact.u);
    EXPECT_LT((again.p_f - ev.contact.p_a).norm(), 1e-12);
  }
  EXPECT_EQ(removed, 1);
  EXPECT_EQ(added, 2);
  EXPECT_EQ(sides, 0.0);  // one on each side
}

// The minima a split added, tracked on: no further events. Two contacts tracked on one point
// (a split's minima come back together): the later is removed as merged.
TEST(ContactSplitTest, SplitMinimaAreStableAndTwoContactsOnOnePointMerge) {
  StageFixture s;
  SurfacePairEval at;
  const SurfaceSurfaceExtremum e = s.L.Contact(&at);
  std::vector<ContactEvent> events;
  s.stage.Run(s.poses, {{0, 1, e.u, e.beta, e.p_f, e.p_g}}, &events);
  std::vector<GlobalContact> minima;
  for (const ContactEvent& ev : events)
    if (ev.kind == ContactEvent::Kind::kAdded) minima.push_back(ev.contact);
  ASSERT_EQ(minima.size(), 2u);
  s.stage.Run(s.poses, minima, &events);
  EXPECT_TRUE(events.empty()) << ToString(events.front().reason);
  s.stage.Run(s.poses, {minima[0], minima[1], minima[0]}, &events);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, ContactEvent::Kind::kRemoved);
  EXPECT_EQ(events[0].reason, ContactEvent::Reason::kMerged);
  EXPECT_EQ(events[0].contact.u, minima[0].u);
}

}  // namespace
}  // namespace tangent::contact
