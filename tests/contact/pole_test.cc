// Poles: a sphere's parameterization collapses a whole row of its net to one point (S_u = 0),
// where N = S_u × S_v vanishes and Newton's matrix is singular. The surface itself is smooth
// there, so the contact must not notice: frames from the limit normal, and extremal solves that
// reach the true gap when the nearest point is on or near the pole, from seeds on and around it.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "contact/extremal.h"
#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

constexpr double kRadius = 0.05;
constexpr double kGap = 0.047;

Vector7d Coordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

TEST(PoleTest, FramesAtAPoleUseTheLimitNormal) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, kRadius);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const BodyPose pose = BodyPose::FromCoordinates(Coordinates({0.1, -0.2, 0.3}, turn));
  for (double v : {0.0, 1.0}) {
    for (double u : {0.0, 0.13, 0.5, 0.77, 1.0}) {
      PlacedSurfacePoint p;
      nurbs::SpanHint hint;
      EvaluatePlaced(sphere, pose, u, v, &hint, &p);
      EXPECT_TRUE(p.pole);
      // The outward normal at a pole of a centred sphere is the radius direction.
      const Eigen::Vector3d radial = (p.world.S - pose.q.head<3>()).normalized();
      EXPECT_LT((p.unit_normal() - radial).norm(), 1e-12) << "u " << u << " v " << v;
      const Eigen::Matrix3d f = ContactFrame(p);
      EXPECT_TRUE(f.allFinite());
      EXPECT_LT((f.transpose() * f - Eigen::Matrix3d::Identity()).norm(), 1e-14);
      EXPECT_NEAR(f.determinant(), 1.0, 1e-14);
      EXPECT_LT((f.col(2) - radial).norm(), 1e-12);
      // Continuous with the frames next to the pole.
      PlacedSurfacePoint q;
      EvaluatePlaced(sphere, pose, u, v == 0.0 ? 1e-6 : 1.0 - 1e-6, &hint, &q);
      EXPECT_FALSE(q.pole);
      EXPECT_LT((ContactFrame(q).col(2) - f.col(2)).norm(), 1e-4);
    }
  }
}

// The unit sphere's south pole over a plane tilted by `tilt` about x: the gap is kGap along
// the plane's normal, the nearest sphere point r·(−n) from the centre, r·sin(tilt) from the
// pole.
struct Layout {
  nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, kRadius);
  nurbs::NurbsSurface plane = nurbs::MakePlanePatch({-0.3, -0.3, 0}, {0.6, 0, 0}, {0, 0.6, 0});
  BodyPose ps, pp;
  Eigen::Vector3d n, nearest;
  explicit Layout(double tilt) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()));
    pp = BodyPose::FromCoordinates(Coordinates({0, 0, 0}, q));
    n = q * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d centre = (kRadius + kGap) * n + Eigen::Vector3d(0.01, -0.02, 0) -
                                   n * n.dot(Eigen::Vector3d(0.01, -0.02, 0));
    ps = BodyPose::FromCoordinates(Coordinates(centre, Eigen::Quaterniond::Identity()));
    nearest = centre - kRadius * n;
  }
};

TEST(PoleTest, SurfaceSolvesReachTheGapOnAndNearAPole) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (double tilt_deg : {0.0, 0.5, 3.0, 10.0}) {
    const Layout l(tilt_deg * std::numbers::pi / 180);
    int ok = 0, total = 0;
    std::vector<Eigen::Vector4d> seeds = {ClosestSamplePair(l.sphere, l.ps, l.plane, l.pp, 16)};
    for (int k = 0; k < 8; ++k) seeds.push_back({uni(rng), 0.0, 0.4 + 0.2 * uni(rng), 0.5});
    for (double dv : {1e-9, 1e-6, 1e-3, 0.02, 0.05}) {
      for (int k = 0; k < 4; ++k) seeds.push_back({uni(rng), dv, 0.4 + 0.2 * uni(rng), 0.5});
    }
    for (const Eigen::Vector4d& seed : seeds) {
      const SurfaceSurfaceExtremum e = SolveSurfaceSurface(l.sphere, l.ps, l.plane, l.pp, seed);
      ++total;
      const bool reached =
          (e.status == ExtremalStatus::kConverged || e.status == ExtremalStatus::kAtBoundary) &&
          e.kind == ExtremumKind::kMinimum && std::abs(e.beta - kGap) < 1e-12 &&
          (e.p_f - l.nearest).norm() < 1e-9 && e.R_WCf.allFinite() &&
          (e.R_WCf.col(2) + l.n).norm() < 1e-9;
      ok += reached;
      EXPECT_TRUE(reached) << "tilt " << tilt_deg << "° seed " << seed.transpose() << ": "
                           << ToString(e.status) << " " << ToString(e.kind) << " beta " << e.beta
                           << " |p - nearest| " << (e.p_f - l.nearest).norm();
    }
    std::printf("tilt %4.1f deg: %d of %d seeds on, near and around the pole reach beta = %.3f\n",
                tilt_deg, ok, total, kGap);
  }
}

TEST(PoleTest, PointSolvesReachThePole) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, kRadius);
  const BodyPose pose =
      BodyPose::FromCoordinates(Coordinates({0, 0, 0}, Eigen::Quaterniond::Identity()));
  for (double tilt_deg : {0.0, 0.2, 3.0}) {
    const double t = tilt_deg * std::numbers::pi / 180;
    const Eigen::Vector3d dir(0, std::sin(t),
                              -std::cos(t));  // from the centre, near the south pole
    const Eigen::Vector3d x = (kRadius + kGap) * dir;
    for (const Eigen::Vector2d& seed : {Eigen::Vector2d(0.3, 0.0), Eigen::Vector2d(0.8, 1e-4),
                                        Eigen::Vector2d(0.1, 0.05), Eigen::Vector2d(0.5, 0.2)}) {
      const PointSurfaceExtremum e = SolvePointSurface(x, sphere, pose, seed);
      EXPECT_TRUE(e.status == ExtremalStatus::kConverged || e.status == ExtremalStatus::kAtBoundary)
          << ToString(e.status) << " tilt " << tilt_deg << " seed " << seed.transpose();
      EXPECT_NEAR(e.distance, kGap, 1e-12) << "tilt " << tilt_deg << " seed " << seed.transpose();
      EXPECT_LT((e.p_f - kRadius * dir).norm(), 1e-9);
      EXPECT_LT((e.R_WCf.col(2) - dir).norm(), 1e-9);
    }
  }
}

}  // namespace
}  // namespace tangent::contact
