// The wires' ground truth (testing/torus_gap.h, testing/tube_gap.h), which the conformal tests,
// bench/hooks_turn and bench/chain_soak judge the contact code by, checked itself against
// closed forms: segment distances against dense samples, circle distances where they are known,
// and centre lines sampled off NURBS tori and tubes against their exact circles and lines.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "nurbs/primitives.h"
#include "testing/conformal_scenes.h"
#include "testing/torus_gap.h"
#include "testing/tube_gap.h"

namespace tangent::testing {
namespace {

TEST(WireGapTest, SegmentDistanceMatchesDenseSamples) {
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto point = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d p0 = point(), q0 = point();
    Eigen::Vector3d p1 = point(), q1 = point();
    if (k % 10 == 1) q1 = q0 + 0.5 * (p1 - p0);  // parallel
    if (k % 10 == 2) p1 = p0;                    // a point against a segment
    constexpr int kSamples = 400;
    double sampled = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kSamples; ++i) {
      for (int j = 0; j <= kSamples; ++j) {
        const double s = double(i) / kSamples, t = double(j) / kSamples;
        sampled = std::min(sampled, (p0 + s * (p1 - p0) - q0 - t * (q1 - q0)).norm());
      }
    }
    const double d = SegmentDistance(p0, p1, q0, q1);
    EXPECT_LE(d, sampled + 1e-12) << k;
    // (The distance is 1-Lipschitz in either point: a sample is within half a spacing of the
    // nearest points.)
    EXPECT_GE(d, sampled - 0.5 * ((p1 - p0).norm() + (q1 - q0).norm()) / kSamples) << k;
  }
}

TEST(WireGapTest, CircleDistanceWhereItIsKnown) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // Concentric in one plane: the radii's difference.
  EXPECT_NEAR(CircleDistance(TorusCircle(1.0, I, Eigen::Vector3d::Zero()),
                             TorusCircle(0.6, I, Eigen::Vector3d::Zero())),
              0.4, 1e-12);
  // Coaxial, 0.3 apart along the axis.
  EXPECT_NEAR(CircleDistance(TorusCircle(1.0, I, Eigen::Vector3d::Zero()),
                             TorusCircle(1.0, I, Eigen::Vector3d(0, 0, 0.3))),
              0.3, 1e-12);
  // Two rings hooked as in kHooksScene, 1.5 apart: touching tubes of 0.45 (gap 0), and turned
  // about the line between their centres the gap stays ≥ 0 while it grows apart.
  const Eigen::Matrix3d upright(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(CircleDistance(TorusCircle(1.2, I, Eigen::Vector3d::Zero()),
                             TorusCircle(1.2, upright, Eigen::Vector3d(1.5, 0, 0))),
              0.9, 1e-12);
  // Moved 2 further along x: unhooked, 3.5 − 2 × 1.2 between the nearest points on the x axis.
  EXPECT_NEAR(CircleDistance(TorusCircle(1.2, I, Eigen::Vector3d::Zero()),
                             TorusCircle(1.2, upright, Eigen::Vector3d(3.5, 0, 0))),
              1.1, 1e-12);
  const double kPose[7] = {1.5e-3, 0, 0, 1, 0, 0, 0};
  EXPECT_NEAR(HooksTrueGap(kPose), 0.0, 1e-15);
}

TEST(WireGapTest, CentreLinesSampledOffNurbsWires) {
  // A torus's centre line is its major circle, and its sections' radius the minor one.
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(1.2e-3, 0.45e-3);
  const Centreline c = SampleCentreline(torus, 0, 400);
  ASSERT_EQ(c.points.size(), 400u);
  EXPECT_NEAR(c.radius, 0.45e-3, 1e-15);
  for (const Eigen::Vector3d& p : c.points) {
    EXPECT_NEAR(p.head<2>().norm(), 1.2e-3, 1e-15);
    EXPECT_NEAR(p.z(), 0.0, 1e-15);
  }
  // Two such tori placed as the hooks: the polylines' distance is the circles' to their chords'
  // sag, R (Δθ)² / 8 with Δθ = 2π / 399.
  const Eigen::Matrix3d upright(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  for (const double x : {1.5e-3, 1.7e-3, 2.5e-3}) {
    const double polyline =
        CentrelineDistance(c, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), c, upright,
                           Eigen::Vector3d(x, 0, 0));
    const double exact =
        CircleDistance(TorusCircle(1.2e-3, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()),
                       TorusCircle(1.2e-3, upright, Eigen::Vector3d(x, 0, 0)));
    const double sag = 1.2e-3 * std::pow(2 * std::numbers::pi / 399, 2) / 8;
    EXPECT_NEAR(polyline, exact, 2 * sag) << x;
  }
  // A straight tube's centre line is its path (from the origin along +y).
  const nurbs::NurbsSurface tube = nurbs::MakeTube({nurbs::PathSegment::Line(0.01)}, 0.5e-3);
  const Centreline s = SampleCentreline(tube, 0, 50);
  EXPECT_NEAR(s.radius, 0.5e-3, 1e-15);
  for (const Eigen::Vector3d& p : s.points) {
    EXPECT_NEAR(p.x(), 0.0, 1e-15);
    EXPECT_NEAR(p.z(), 0.0, 1e-15);
  }
  EXPECT_NEAR((s.points.back() - s.points.front()).norm(), 0.01, 1e-15);
  // A paperclip's (chain_soak's wires): in its plane, of its wire's radius, and as long as its
  // path to the chords' shortfall.
  const std::vector<nurbs::PathSegment> path = nurbs::PaperclipPath();
  double length = 0.0;
  for (const nurbs::PathSegment& p : path) {
    length += p.kind == nurbs::PathSegment::Kind::kLine ? p.length_or_radius
                                                        : p.length_or_radius * std::abs(p.angle);
  }
  const Centreline clip =
      SampleCentreline(nurbs::MakeTube(path, nurbs::kPaperclipWireRadius), 0, 4000);
  EXPECT_NEAR(clip.radius, nurbs::kPaperclipWireRadius, 1e-15);
  double polyline = 0.0;
  for (size_t i = 0; i < clip.points.size(); ++i) {
    EXPECT_NEAR(clip.points[i].z(), 0.0, 1e-15);
    if (i > 0) polyline += (clip.points[i] - clip.points[i - 1]).norm();
  }
  EXPECT_NEAR(polyline, length, 1e-6 * length);
}

}  // namespace
}  // namespace tangent::testing
