// Tracking: predictor + one corrector per step follows the extremal pair along a hand-like
// trajectory at servo-rate step sizes, allocation free, with the defined states at domain edges,
// on jumps, and at singular configurations.

#include "contact/tracker.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>

#include "testing/alloc_counter.h"
#include "testing/contact_scenes.h"

namespace tangent::contact {
namespace {

using testing::Coordinates;

struct ShearedTorus {
  nurbs::NurbsSurface sheared =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, 0.01, true);
  nurbs::NurbsSurface torus = nurbs::MakeTorus(0.04, 0.01);
  // The patch face-down over the torus tube; t moves it along a smooth path (1 s of a hand).
  Vector7d Patch(double t) const {
    const Eigen::Quaterniond rot(
        Eigen::AngleAxisd(0.2 + 0.3 * t, Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(std::numbers::pi + 0.1 * std::sin(3 * t), Eigen::Vector3d::UnitX()));
    return Coordinates({0.004 * std::sin(2 * t), 0.003 * t, 0.025 - 0.006 * t}, rot);
  }
  Vector7d Torus() const {
    return Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  }
  /// The extremum at the path's start, solved from the closest samples.
  SurfaceSurfaceExtremum Start() const {
    const BodyPose pf = BodyPose::FromCoordinates(Patch(0)),
                   pg = BodyPose::FromCoordinates(Torus());
    return SolveSurfaceSurface(sheared, pf, torus, pg,
                               ClosestSamplePair(sheared, pf, torus, pg, 40));
  }
};

TEST(TrackerTest, FollowsTheExactExtremumAtServoRateWithoutAllocating) {
  const ShearedTorus s;
  const BodyPose pg = BodyPose::FromCoordinates(s.Torus());
  const SurfaceSurfaceExtremum start = s.Start();
  ASSERT_EQ(start.status, ExtremalStatus::kConverged);
  ContactTracker tracker(s.sheared, s.torus);
  ASSERT_EQ(tracker.Reset(s.Patch(0), s.Torus(), start.u), TrackStatus::kTracked);
  // 1000 steps of 1 ms: the patch moves ~7 mm and turns ~0.3 rad, ~10 um per step.
  std::vector<Vector7d> path;
  for (int k = 1; k <= 1000; ++k) path.push_back(s.Patch(k * 1e-3));
  std::vector<Eigen::Vector4d> tracked;
  tracked.reserve(path.size());
  const long before = tangent::testing::AllocationCount();
  int not_tracked = 0;
  for (const Vector7d& q : path) {
    not_tracked += tracker.Step(q, s.Torus()) != TrackStatus::kTracked;
    tracked.push_back(tracker.u());
  }
  EXPECT_EQ(tangent::testing::AllocationCount() - before, 0);
  EXPECT_EQ(not_tracked, 0);
  // Against a full solve at every 50th step: one corrector per step keeps the error at the
  // level of the predictor's O(Δq²) residual squared, far below 1e-10 in parameters.
  double worst = 0.0;
  for (size_t k = 49; k < path.size(); k += 50) {
    const SurfaceSurfaceExtremum exact =
        SolveSurfaceSurface(s.sheared, BodyPose::FromCoordinates(path[k]), s.torus, pg, tracked[k]);
    ASSERT_EQ(exact.status, ExtremalStatus::kConverged);
    worst = std::max(worst, (exact.u - tracked[k]).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-10);
  std::printf("tracking 1000 servo steps: worst parameter error vs a full solve %.1e\n", worst);
}

// The corrector count (TrackerOptions::corrector_steps, swept by bench/speed_error): with none
// the tracker's point is the prediction, first order in the step; each corrector squares the
// error (Newton), until rounding. Measured against a full solve along the same path with 3x
// larger steps (~30 µm, 1 mrad a step) so the prediction's error is visible.
TEST(TrackerTest, EachCorrectorStepSquaresTheError) {
  const ShearedTorus s;
  const BodyPose pg = BodyPose::FromCoordinates(s.Torus());
  const SurfaceSurfaceExtremum start = s.Start();
  ASSERT_EQ(start.status, ExtremalStatus::kConverged);
  double worst[4] = {0, 0, 0, 0};
  for (int c = 0; c <= 3; ++c) {
    TrackerOptions options;
    options.corrector_steps = c;
    ContactTracker tracker(s.sheared, s.torus, options);
    ASSERT_EQ(tracker.Reset(s.Patch(0), s.Torus(), start.u), TrackStatus::kTracked);
    for (int k = 1; k <= 300; ++k) {
      const Vector7d q = s.Patch(k * 3e-3);
      ASSERT_EQ(tracker.Step(q, s.Torus()), TrackStatus::kTracked) << c << " step " << k;
      const SurfaceSurfaceExtremum exact =
          SolveSurfaceSurface(s.sheared, BodyPose::FromCoordinates(q), s.torus, pg, tracker.u());
      worst[c] = std::max(worst[c], (tracker.u() - exact.u).cwiseAbs().maxCoeff());
    }
  }
  std::printf("tracker error in parameters, 0–3 correctors: %.1e %.1e %.1e %.1e\n", worst[0],
              worst[1], worst[2], worst[3]);
  // Without a corrector the error accumulates at first order (the next prediction starts from
  // the last one's point); one corrector brings it to the prediction error squared; two and
  // three to rounding.
  EXPECT_GT(worst[0], 1e-6);
  EXPECT_LT(worst[1], 1e-3 * worst[0]);
  EXPECT_LT(worst[2], 1e-12);
  EXPECT_LT(worst[3], 1e-12);
}

TEST(TrackerTest, ReportsBoundaryJumpsAndSingularities) {
  const nurbs::NurbsSurface sphere = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface patch =
      nurbs::MakePlanePatch({-0.05, -0.05, 0}, {0.1, 0, 0}, {0, 0.1, 0});
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  const Vector7d plane = Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  ContactTracker tracker(sphere, patch);
  const SurfaceSurfaceExtremum e =
      SolveSurfaceSurface(sphere, BodyPose::FromCoordinates(Coordinates({0, 0, 0.06}, turn)), patch,
                          BodyPose::FromCoordinates(plane), Eigen::Vector4d(0.75, 0.5, 0.5, 0.5));
  ASSERT_EQ(tracker.Reset(Coordinates({0, 0, 0.06}, turn), plane, e.u), TrackStatus::kTracked);
  // Slide the sphere sideways past the patch's edge at x = 0.05: the plane point stops there.
  TrackStatus last = TrackStatus::kTracked;
  for (int k = 1; k <= 80; ++k) last = tracker.Step(Coordinates({0.001 * k, 0, 0.06}, turn), plane);
  EXPECT_EQ(last, TrackStatus::kAtBoundary);
  EXPECT_EQ(tracker.u()[2], 1.0);
  // A jump far beyond the predictor's reach is reported lost, not followed to another point.
  ContactTracker jumper(sphere, patch);
  jumper.Reset(Coordinates({0, 0, 0.06}, turn), plane, e.u);
  EXPECT_EQ(
      jumper.Step(
          Coordinates({0, 0, 0.06},
                      Eigen::Quaterniond(Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitY())) * turn),
          plane),
      TrackStatus::kLost);
  // Concentric spheres: a continuum of extremal pairs, ∂F/∂u singular.
  const nurbs::NurbsSurface outer = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.1);
  ContactTracker concentric(sphere, outer);
  EXPECT_EQ(concentric.Reset(Coordinates(Eigen::Vector3d::Zero(), turn), plane,
                             Eigen::Vector4d(0.3, 0.5, 0.3, 0.5)),
            TrackStatus::kSingular);
}

}  // namespace
}  // namespace tangent::contact
