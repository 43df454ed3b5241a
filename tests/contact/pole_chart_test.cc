// The tangent-plane chart at a smooth pole (contact/pole_chart.h): its inverse lands on the
// point it was given, and its partials are the derivatives of the map they claim to be, on,
// next to and away from the pole, checked by central differences through the chart's own
// inverse.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "contact/extremal.h"
#include "contact/pole_chart.h"
#include "contact/tracker.h"
#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

// The sphere with its control net scaled by (1, 1.5, 0.7): an ellipsoid, smooth at its poles
// but not a surface of revolution, so its angle parameter is not the angle round the pole.
nurbs::NurbsSurface Ellipsoid() {
  const nurbs::NurbsSurface s = nurbs::MakeSphere({0, 0, 0}, 0.05);
  std::vector<Eigen::Vector4d> w = s.weighted_points();
  for (Eigen::Vector4d& p : w) p.head<3>() = p.head<3>().cwiseProduct(Eigen::Vector3d(1, 1.5, 0.7));
  return nurbs::NurbsSurface::FromHomogeneous(s.knots_u(), s.knots_v(), w);
}

struct Case {
  const char* name;
  nurbs::NurbsSurface surface;
};

std::vector<Case> Cases() {
  return {{"sphere", nurbs::MakeSphere({0.01, -0.02, 0.03}, 0.05)}, {"ellipsoid", Ellipsoid()}};
}

BodyPose Turned() {
  Vector7d q;
  const Eigen::Quaterniond r(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  q << 0.1, -0.2, 0.3, r.w(), r.x(), r.y(), r.z();
  return BodyPose::FromCoordinates(q);
}

TEST(PoleChartTest, OnlySmoothPolesHaveACharts) {
  PoleChart c;
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, 0.05);
  EXPECT_TRUE(FindPoleChart(sphere, {0.3, 0.01}, kChartEnter, &c));
  EXPECT_EQ(c.across, 1);
  EXPECT_EQ(c.bound, 0.0);
  EXPECT_LT((c.n - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);  // the south pole's normal
  EXPECT_NEAR(c.e1.cross(c.e2).dot(c.n), 1.0, 1e-15);
  EXPECT_TRUE(FindPoleChart(sphere, {0.3, 0.99}, kChartEnter, &c));
  EXPECT_LT((c.n - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12);
  EXPECT_FALSE(FindPoleChart(sphere, {0.3, 0.5}, kChartEnter, &c));  // the equator
  // A cone's apex is a vertex: no tangent plane, no chart. Its base rim is no pole.
  const nurbs::NurbsSurface cone = nurbs::MakeCone(0.05, 0.08);
  EXPECT_FALSE(FindPoleChart(cone, {0.3, 0.001}, kChartEnter, &c));
  EXPECT_FALSE(FindPoleChart(cone, {0.3, 0.999}, kChartEnter, &c));
}

// The chart's inverse returns the point it was given the coordinates of: the same angle away from
// the pole, the point itself when the coordinates cross the pole (the angle half a turn on).
TEST(PoleChartTest, TheInverseLandsOnThePoint) {
  for (const Case& k : Cases()) {
    for (double v0 : {0.0, 1.0}) {
      PoleChart c;
      ASSERT_TRUE(FindPoleChart(k.surface, {0.2, v0}, kChartEnter, &c)) << k.name;
      nurbs::SpanHint hint;
      double worst = 0.0;
      for (double rho : {0.0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-2, 0.04}) {
        for (int i = 0; i < 24; ++i) {
          const double u = (i + 0.3) / 24.0;
          const Eigen::Vector2d uv(u, v0 + c.inward * rho);
          const Eigen::Vector2d xy = ChartCoordinates(k.surface, c, uv, &hint);
          // From a guess on the far side of the pole, and from the point's own parameters.
          for (const Eigen::Vector2d& guess :
               {Eigen::Vector2d(std::fmod(u + 0.5, 1.0), uv[1]), Eigen::Vector2d(uv)}) {
            Eigen::Vector2d back;
            ASSERT_TRUE(ChartParameters(k.surface, c, xy, guess, &hint, &back))
                << k.name << " rho " << rho << " u " << u;
            const Eigen::Vector3d a = k.surface.Evaluate(uv[0], uv[1], 0).S;
            const Eigen::Vector3d b = k.surface.Evaluate(back[0], back[1], 0).S;
            worst = std::max(worst, (a - b).norm());
          }
        }
      }
      std::printf("%s, pole v = %g: inverse worst %.3g m\n", k.name, v0, worst);
      EXPECT_LT(worst, 1e-15);  // within a few ulp of a 5 cm surface's coordinates
    }
  }
}

// First partials against central differences of the point, second partials against central
// differences of the first partials, stepping the chart coordinates (through its inverse).
TEST(PoleChartTest, PartialsAreTheChartsDerivatives) {
  const BodyPose pose = Turned();
  for (const Case& k : Cases()) {
    for (double v0 : {0.0, 1.0}) {
      PoleChart c;
      ASSERT_TRUE(FindPoleChart(k.surface, {0.2, v0}, kChartEnter, &c));
      nurbs::SpanHint hint;
      double worst1 = 0.0, worst2 = 0.0, worst_n = 0.0;
      for (double rho : {0.0, 1e-7, 1e-3, 1e-2, 0.04}) {
        for (int i = 0; i < 12; ++i) {
          const double u = (i + 0.1) / 12.0;
          const Eigen::Vector2d uv(u, v0 + c.inward * rho);
          PlacedSurfacePoint at;
          EvaluateCharted(k.surface, c, pose, uv, &hint, &at);
          EXPECT_TRUE(at.charted);
          // The chart's normal is the surface's (the limit normal at the pole).
          PlacedSurfacePoint plain;
          EvaluatePlaced(k.surface, pose, uv[0], uv[1], &hint, &plain);
          if (rho == 0.0 || rho > 1e-4) {
            worst_n = std::max(worst_n, (at.N_W.normalized() - plain.unit_normal()).norm());
          }
          const Eigen::Vector2d xy = ChartCoordinates(k.surface, c, uv, &hint);
          const double h = 1e-5 * 0.05;
          for (int dir = 0; dir < 2; ++dir) {
            PlacedSurfacePoint side[2];
            for (int s = 0; s < 2; ++s) {
              Eigen::Vector2d x2 = xy;
              x2[dir] += (s == 0 ? -h : h);
              Eigen::Vector2d uv2;
              ASSERT_TRUE(ChartParameters(k.surface, c, x2, uv, &hint, &uv2));
              EvaluateCharted(k.surface, c, pose, uv2, &hint, &side[s]);
            }
            const Eigen::Vector3d fd1 = (side[1].world.S - side[0].world.S) / (2 * h);
            const Eigen::Vector3d& an1 = dir == 0 ? at.world.S_u : at.world.S_v;
            worst1 = std::max(worst1, (fd1 - an1).norm() / an1.norm());
            const Eigen::Vector3d fd_x = (side[1].world.S_u - side[0].world.S_u) / (2 * h);
            const Eigen::Vector3d fd_y = (side[1].world.S_v - side[0].world.S_v) / (2 * h);
            const Eigen::Vector3d& an_x = dir == 0 ? at.world.S_uu : at.world.S_uv;
            const Eigen::Vector3d& an_y = dir == 0 ? at.world.S_uv : at.world.S_vv;
            // Curvature scale: 1/R of a 5 cm surface.
            worst2 = std::max(worst2, std::max((fd_x - an_x).norm(), (fd_y - an_y).norm()) * 0.05);
          }
        }
      }
      std::printf("%s, pole v = %g: first partials %.3g, second %.3g, normal %.3g\n", k.name, v0,
                  worst1, worst2, worst_n);
      EXPECT_LT(worst1, 1e-8);
      EXPECT_LT(worst2, 1e-4);  // within kSecondOrderRho of the pole they are taken at it
      EXPECT_LT(worst_n, 1e-9);
    }
  }
}

Vector7d Coordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

// A 5 cm sphere over a plane tilted by `tilt` about x, `gap` apart; `turn` turns the sphere
// about x before it is placed, so with 90° its equator faces the plane instead of its pole.
struct SphereOverPlane {
  nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, 0.05);
  nurbs::NurbsSurface plane = nurbs::MakePlanePatch({-0.3, -0.3, 0}, {0.6, 0, 0}, {0, 0.6, 0});
  BodyPose ps, pp;
  Eigen::Vector3d n;
  SphereOverPlane(double tilt, double gap, double turn) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()));
    pp = BodyPose::FromCoordinates(Coordinates({0, 0, 0}, q));
    n = q * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d centre = (0.05 + gap) * n + Eigen::Vector3d(0.01, -0.02, 0) -
                                   n * n.dot(Eigen::Vector3d(0.01, -0.02, 0));
    const Eigen::Quaterniond t(Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitX()));
    ps = BodyPose::FromCoordinates(Coordinates(centre, t));
  }
};

// Issue 34: continuation solves (the servo's re-solves: kContinuation, seeds within 2 % of each
// domain of the answer) converge as fast at and next to a pole as at the equator. Before the
// chart, Newton in (longitude, latitude) was linear there: median 9, worst 20 steps 0.004 in v
// from the pole against 4 and 5 at the equator (docs/contact.md, "Poles").
TEST(PoleChartTest, ContinuationSolvesConvergeAsFastAtAPoleAsAtTheEquator) {
  std::mt19937_64 rng(34);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  int equator_worst = 0;
  for (double turn : {std::numbers::pi / 2, 0.0}) {
    for (double tilt : {0.0, 0.003, 0.01, 0.05}) {
      for (double gap : {0.0, 0.003}) {
        const SphereOverPlane l(tilt, gap, turn);
        const SurfaceSurfaceExtremum truth = SolveSurfaceSurface(
            l.sphere, l.ps, l.plane, l.pp, ClosestSamplePair(l.sphere, l.ps, l.plane, l.pp, 16));
        ASSERT_EQ(truth.status, ExtremalStatus::kConverged);
        ASSERT_NEAR(truth.beta, gap, 1e-12);
        std::vector<int> steps;
        int ok = 0;
        for (int k = 0; k < 200; ++k) {
          Eigen::Vector4d seed = truth.u;
          for (int i = 0; i < 4; ++i) seed[i] += jitter(rng);
          seed = IntoPairDomain(l.sphere, l.plane, seed);
          const SurfaceSurfaceExtremum e =
              SolveSurfaceSurface(l.sphere, l.ps, l.plane, l.pp, seed, kContinuation);
          const bool reached =
              e.status == ExtremalStatus::kConverged && std::abs(e.beta - gap) <= 1e-12 &&
              std::abs(e.R_WCf.col(2).norm() - 1.0) < 1e-12 && (e.R_WCf.col(2) + l.n).norm() < 1e-9;
          EXPECT_TRUE(reached) << "turn " << turn << " tilt " << tilt << " gap " << gap << " seed "
                               << seed.transpose() << ": " << ToString(e.status) << " beta "
                               << e.beta;
          ok += reached;
          steps.push_back(e.iterations);
        }
        std::sort(steps.begin(), steps.end());
        std::printf(
            "%s, tilt %.3f rad, gap %.3f: %d of 200 reach beta; steps median %d, worst %d\n",
            turn == 0.0 ? "pole   " : "equator", tilt, gap, ok, steps[100], steps.back());
        if (turn != 0.0) {
          equator_worst = std::max(equator_worst, steps.back());
        } else {
          EXPECT_LE(steps.back(), equator_worst);
        }
      }
    }
  }
}

// Issue 34: a contact dragged across a pole stays tracked. The sphere rolls over a fixed plane
// (turning about a horizontal axis while its centre slides), so the contact point runs along a
// meridian through its south pole, or along a path passing `miss` beside it, where the angle
// parameter swings half a turn. Each step is the servo's: the tracker's prediction and one
// correction, taken when the contact equations hold there (ExtremumAt in the tracker's charts).
// Before the chart the tracker was singular at the pole and lost next to it, and every step
// was a full solve.
TEST(PoleChartTest, AContactDraggedAcrossAPoleStaysTracked) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, 0.05);
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.3, -0.3, 0}, {0.6, 0, 0}, {0, 0.6, 0});
  const BodyPose fixed = BodyPose::FromCoordinates(Coordinates({0, 0, 0}, {1, 0, 0, 0}));
  for (double gap : {0.0, 0.002}) {
    for (double miss : {0.0, 1e-7, 1e-4, 1e-2}) {
      ContactTracker tracker(sphere, plane);
      // The turn about x from −0.1 to 0.1 rad, with a tilt `miss` about y (the path's offset).
      auto pose_at = [&](double a) {
        const Eigen::Quaterniond q =
            Eigen::Quaterniond(Eigen::AngleAxisd(miss, Eigen::Vector3d::UnitY())) *
            Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()));
        return Coordinates({0.01, 0.05 * a, 0.05 + gap}, q);
      };
      const int n = 400;
      int tracked = 0, solves = 0;
      double worst_beta = 0.0, worst_point = 0.0, nearest_pole = 1.0;
      Eigen::Vector4d u = SolveSurfaceSurface(sphere, BodyPose::FromCoordinates(pose_at(-0.1)),
                                              plane, fixed, Eigen::Vector4d(0.25, 0.05, 0.5, 0.5))
                              .u;
      bool tracking = false;
      for (int k = 0; k <= n; ++k) {
        const Vector7d q = pose_at(-0.1 + 0.2 * k / n);
        const BodyPose pose = BodyPose::FromCoordinates(q);
        SurfaceSurfaceExtremum e;
        SurfacePairEval at;
        bool done = false;
        if (tracking && tracker.Step(q, fixed.q) == TrackStatus::kTracked) {
          e = ExtremumAt(sphere, pose, plane, fixed, tracker.u(), 1e-12, &at, &tracker.charts());
          done = e.status == ExtremalStatus::kConverged;
        }
        if (!done) {
          e = SolveSurfaceSurface(sphere, pose, plane, fixed, u, kContinuation, &at);
          tracking = tracker.Reset(q, fixed.q, e.u) == TrackStatus::kTracked;
          ++solves;
        } else {
          ++tracked;
        }
        worst_beta = std::max(worst_beta, std::abs(e.beta - gap));
        const Eigen::Vector3d lowest = q.head<3>() - Eigen::Vector3d(0, 0, 0.05);
        worst_point = std::max(worst_point, (e.p_f - lowest).norm());
        nearest_pole = std::min(nearest_pole, e.u[1]);
        u = e.u;
      }
      std::printf(
          "gap %.3f, path %.0e rad beside the pole (nearest v %.1e): %d of %d steps tracked, %d "
          "solves; beta to %.1e, point to %.1e m\n",
          gap, miss, nearest_pole, tracked, n + 1, solves, worst_beta, worst_point);
      EXPECT_EQ(solves, 1);  // the start only
      EXPECT_LT(worst_beta, 1e-12);
      EXPECT_LT(worst_point, 1e-9);
    }
  }
}

}  // namespace
}  // namespace tangent::contact
