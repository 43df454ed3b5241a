// contact/trimmed.h: the distance on a trimmed surface's material. A ball over a hole whose
// nearest rim point is a corner of the loop (a wedge of material pointing into the hole): the
// edge's extremum is held at the joint of two pieces, both pushing into it, and that is the
// contact (converged, the corner point), not a border of the loop; a ball over a circular
// hole measured at the rim through every quarter point of the circle (full knots where the
// circle is C¹); and the circle followed across its closure, which is no joint (one periodic
// piece: the edge's Newton wraps round instead of stopping there).

#include "contact/trimmed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

constexpr double mm = 1e-3;

BodyPose At(const Eigen::Vector3d& p) {
  Vector7d q;
  q << p, 1, 0, 0, 0;
  return BodyPose::FromCoordinates(q);
}

SurfaceSurfaceExtremum Face(const nurbs::NurbsSurface& plate, const nurbs::NurbsSurface& ball,
                            const BodyPose& pose) {
  // The plane's point under the ball's lowest point (the face pair).
  const Eigen::Vector3d c = pose.q.head<3>();
  return SolveSurfaceSurface(plate, At(Eigen::Vector3d::Zero()), ball, pose,
                             Eigen::Vector4d(c.x() / (40 * mm), c.y() / (40 * mm), 0.5, 0.05));
}

/// A 40 mm plate (the plane z = 0) with a round hole 10 mm across at (20, 20) mm, and a 4 mm
/// ball held 0.05 mm from the rim with its centre 2.5 mm from the hole's axis.
struct RoundHole {
  const nurbs::NurbsSurface plate =
      nurbs::MakePlanePatch({0, 0, 0}, {40 * mm, 0, 0}, {0, 40 * mm, 0});
  const nurbs::TrimmedDomain trim{
      {0, 0},
      {1, 1},
      std::nullopt,
      {nurbs::TrimLoop{{nurbs::MakeCircle2d({0.5, 0.5}, 0.125, true)}}}};
  const TrimEdges edges{&plate, &trim};
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 4 * mm);
  const double z = std::sqrt(4.05 * 4.05 - 2.5 * 2.5) * mm;

  /// The rim measured with the ball's centre at angle `a` round the hole's axis.
  TrimmedMeasure Measure(double a, const TrimEdges::Edge* from = nullptr) const {
    const BodyPose pose =
        At({20 * mm + 2.5 * mm * std::cos(a), 20 * mm + 2.5 * mm * std::sin(a), z});
    return MeasureTrimmed(edges, At(Eigen::Vector3d::Zero()), ball, pose, Face(plate, ball, pose),
                          from);
  }
};

TEST(TrimmedTest, ACornerOfTheLoopIsAContact) {
  const nurbs::NurbsSurface plate =
      nurbs::MakePlanePatch({0, 0, 0}, {40 * mm, 0, 0}, {0, 40 * mm, 0});
  // A hole with a wedge of material pointing into it at (0.5, 0.5) (clockwise: material left).
  const nurbs::TrimmedDomain trim(
      {0, 0}, {1, 1}, std::nullopt,
      {nurbs::TrimLoop{{nurbs::MakePolyline2d(
          {{0.3, 0.3}, {0.3, 0.7}, {0.5, 0.5}, {0.7, 0.7}, {0.7, 0.3}, {0.3, 0.3}})}}});
  const TrimEdges edges(&plate, &trim);
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 4 * mm);
  // The ball under the wedge's tip (20, 20, 0) mm, 0.05 mm from it.
  const double z = std::sqrt(4.05 * 4.05 - 2.0 * 2.0) * mm;
  const BodyPose pose = At({20 * mm, 18 * mm, z});
  const SurfaceSurfaceExtremum face = Face(plate, ball, pose);
  ASSERT_FALSE(trim.Contains(face.u.head<2>()));
  const TrimmedMeasure m = MeasureTrimmed(edges, At(Eigen::Vector3d::Zero()), ball, pose, face);
  EXPECT_TRUE(m.on_edge);
  EXPECT_EQ(m.status, ExtremalStatus::kConverged);
  EXPECT_NEAR(m.beta, 0.05 * mm, 1e-12);
  EXPECT_LT((m.p_f - Eigen::Vector3d(20 * mm, 20 * mm, 0)).norm(), 1e-12);
}

TEST(TrimmedTest, ARoundRimIsMeasuredThroughItsQuarterPoints) {
  const RoundHole hole;
  int worst_status = 0;
  double worst_beta = 0.0;
  // Round the rim in 1/720 turns, and at each quarter point ± 1e-12 rad.
  for (int k = 0; k <= 724; ++k) {
    const double a = k <= 720 ? 2 * std::numbers::pi * k / 720
                              : (k - 721) * std::numbers::pi / 2 + ((k % 2) ? 1e-12 : -1e-12);
    const TrimmedMeasure m = hole.Measure(a);
    ASSERT_TRUE(m.on_edge) << k;
    worst_status = std::max(worst_status, static_cast<int>(m.status));
    worst_beta = std::max(worst_beta, std::abs(m.beta - 0.05 * mm));
  }
  EXPECT_EQ(worst_status, static_cast<int>(ExtremalStatus::kConverged));
  EXPECT_LT(worst_beta, 1e-12);
}

TEST(TrimmedTest, ACircleIsOnePeriodicPieceFollowedAcrossItsClosure) {
  const RoundHole hole;
  const TrimEdges& edges = hole.edges;
  ASSERT_EQ(edges.loops().size(), 1u);
  ASSERT_EQ(edges.loops()[0].size(), 1u);  // its quarter points' full knots are C¹: not cut
  EXPECT_TRUE(edges.loops()[0][0].periodic);
  // A polyline's vertices stay joints, and an open run of pieces is not periodic.
  const nurbs::TrimmedDomain square(
      {0, 0}, {1, 1}, std::nullopt,
      {nurbs::TrimLoop{
          {nurbs::MakePolyline2d({{0.3, 0.3}, {0.3, 0.7}, {0.7, 0.7}, {0.7, 0.3}, {0.3, 0.3}})}}});
  const TrimEdges square_edges(&hole.plate, &square);
  ASSERT_EQ(square_edges.loops()[0].size(), 4u);
  EXPECT_FALSE(square_edges.loops()[0][0].periodic);

  // The ball slides along the rim through the circle's closure (angle 0: τ = 0 ≡ 1), each
  // measure following the last edge: it stays on the one piece, never held at a bound, and
  // each solve converges in a few Newton steps.
  TrimEdges::Edge last;
  bool have_last = false;
  int most_iterations = 0;
  double worst_beta = 0.0;
  for (int k = -20; k <= 20; ++k) {
    const TrimmedMeasure m = hole.Measure(1e-3 * k, have_last ? &last : nullptr);
    ASSERT_TRUE(m.on_edge) << k;
    EXPECT_EQ(m.status, ExtremalStatus::kConverged) << k;
    EXPECT_FALSE(m.edge.ext.at_bound[2]) << k;
    EXPECT_EQ(m.edge.piece, 0) << k;
    if (have_last) most_iterations = std::max(most_iterations, m.edge.ext.iterations);
    worst_beta = std::max(worst_beta, std::abs(m.beta - 0.05 * mm));
    last = m.edge;
    have_last = true;
  }
  EXPECT_LE(most_iterations, 4);
  EXPECT_LT(worst_beta, 1e-12);
}

}  // namespace
}  // namespace tangent::contact
