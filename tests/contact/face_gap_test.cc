// Flat faces against each other (contact/face_gap.h) and the global stage's face pairs
// (GlobalContactStage::FindFaces): the lowest corner lying over the other face against dense
// samples of the face, and the pair found, kept and released as the faces meet and part.

#include "contact/face_gap.h"

#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "contact/global.h"
#include "nurbs/offset.h"
#include "nurbs/primitives.h"
#include "testing/contact_scenes.h"

namespace tangent::contact {
namespace {

constexpr double mm = 1e-3;

BodyPose At(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return BodyPose::FromCoordinates(testing::Coordinates(p, q));
}

// The least height over `other` (along its normal, at its closest point, over its domain only)
// of 201 x 201 samples of `face`: what the corners must match when every corner of the face lies
// over the other.
double SampledLowest(const nurbs::NurbsSurface& face, const BodyPose& pf,
                     const nurbs::NurbsSurface& other, const BodyPose& po) {
  double lowest = INFINITY;
  for (int i = 0; i <= 200; ++i) {
    for (int j = 0; j <= 200; ++j) {
      const Eigen::Vector3d x = pf.Point(face.Evaluate(i / 200.0, j / 200.0, 0).S);
      const PointSurfaceExtremum e = SolvePointSurface(x, other, po, {0.5, 0.5});
      if (e.status == ExtremalStatus::kConverged) lowest = std::min(lowest, e.distance);
    }
  }
  return lowest;
}

TEST(FaceGapTest, TheLowestCornerIsTheFacesLeastHeightOverTheOther) {
  // A 20 mm face (normal down) over a 60 mm floor (normal up), tilted and moved at random with
  // its corners over the floor; and the same pair the other way round (the floor's corners lie
  // over nothing, the face's are taken as g's).
  const nurbs::NurbsSurface floor =
      nurbs::MakePlanePatch({-30 * mm, -30 * mm, 0}, {60 * mm, 0, 0}, {0, 60 * mm, 0});
  const nurbs::NurbsSurface face =
      nurbs::MakePlanePatch({-10 * mm, -10 * mm, 0}, {0, 20 * mm, 0}, {20 * mm, 0, 0});
  const auto qf = nurbs::FlatQuadOf(floor), qb = nurbs::FlatQuadOf(face);
  ASSERT_TRUE(qf && qb);
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> off(-1.0, 1.0);
  const BodyPose ground = At(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  for (int trial = 0; trial < 12; ++trial) {
    const Eigen::Quaterniond tilt(Eigen::AngleAxisd(
        0.15 * off(rng), Eigen::Vector3d(off(rng), off(rng), 0.2 * off(rng)).normalized()));
    const BodyPose box =
        At({8 * mm * off(rng), 8 * mm * off(rng), 2 * mm + 1.5 * mm * off(rng)}, tilt);
    const double sampled = SampledLowest(face, box, floor, ground);
    const FaceCorner low = LowestCorner(floor, *qf, ground, face, *qb, box);
    ASSERT_TRUE(low.found);
    EXPECT_FALSE(low.of_f);
    EXPECT_LE(low.beta, sampled + 1e-15);   // no sample of the face lies lower
    EXPECT_NEAR(low.beta, sampled, 1e-12);  // and the corner is one of them
    EXPECT_NEAR(low.beta, low.p_g.z(), 1e-15);
    EXPECT_NEAR(low.p_f.z(), 0.0, 1e-15);
    EXPECT_LT((low.p_g - box.Point(qb->points[static_cast<size_t>(low.corner)])).norm(), 1e-15);
    EXPECT_LT((low.u.head<2>() - Eigen::Vector2d((low.p_f.x() + 30 * mm) / (60 * mm),
                                                 (low.p_f.y() + 30 * mm) / (60 * mm)))
                  .norm(),
              1e-12);
    // The pair the other way round: the same corner, as f's.
    const FaceCorner swapped = LowestCorner(face, *qb, box, floor, *qf, ground);
    ASSERT_TRUE(swapped.found);
    EXPECT_TRUE(swapped.of_f);
    EXPECT_EQ(swapped.corner, low.corner);
    EXPECT_NEAR(swapped.beta, low.beta, 1e-15);
  }
  // Wholly beyond the floor's edge: no corner lies over it.
  const FaceCorner beyond = LowestCorner(floor, *qf, ground, face, *qb,
                                         At({60 * mm, 0, 1 * mm}, Eigen::Quaterniond::Identity()));
  EXPECT_FALSE(beyond.found);
}

TEST(FaceGapTest, TheStageFindsKeepsAndReleasesAFacePairByItsCorners) {
  const nurbs::NurbsSurface floor =
      nurbs::MakePlanePatch({-30 * mm, -30 * mm, 0}, {60 * mm, 0, 0}, {0, 60 * mm, 0});
  const nurbs::NurbsSurface face =
      nurbs::MakePlanePatch({-10 * mm, -10 * mm, 0}, {0, 20 * mm, 0}, {20 * mm, 0, 0});
  const nurbs::OffsetMesh floor_mesh = nurbs::MakeOffsetMesh(floor, 20e-6, 0.25e-3, 0.5e-3);
  const nurbs::OffsetMesh face_mesh = nurbs::MakeOffsetMesh(face, 20e-6, 0.25e-3, 0.5e-3);
  GlobalOptions options;
  GlobalContactStage stage({{0, &floor, &floor_mesh, nullptr}, {1, &face, &face_mesh, nullptr}},
                           {{0, 1}}, options);
  const BodyPose ground = At(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  std::vector<ContactEvent> events;
  GlobalStats stats;
  // Parallel, 0.05 mm over the floor: found (their offsets, parallel sheets, never cross).
  stage.Run({ground, At({0, 0, 0.05 * mm}, Eigen::Quaterniond::Identity())}, {}, &events, &stats);
  EXPECT_EQ(stats.triangle_pairs, 0);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, ContactEvent::Kind::kAdded);
  EXPECT_NEAR(events[0].contact.beta, 0.05 * mm, 1e-15);
  // Tilted 0.7° about y: the lowest corners, at x = +10 mm, found 0.05 mm over the floor.
  const Eigen::Quaterniond tilt(
      Eigen::AngleAxisd(0.7 * std::numbers::pi / 180, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d lowest_at(10 * mm, 0, 0);
  const BodyPose tilted = At(Eigen::Vector3d(0, 0, 0.05 * mm) - tilt * lowest_at + lowest_at, tilt);
  stage.Run({ground, tilted}, {}, &events, &stats);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0].contact.beta, 0.05 * mm, 1e-15);
  EXPECT_NEAR(events[0].contact.p_b.x(), 10 * mm, 1e-15);
  // Tracked, it is kept within the release distance (0.2 mm) and removed beyond it, or when no
  // corner lies over the floor.
  const GlobalContact tracked = events[0].contact;
  stage.Run({ground, At({0, 0, 0.15 * mm}, Eigen::Quaterniond::Identity())}, {tracked}, &events,
            &stats);
  EXPECT_TRUE(events.empty());
  stage.Run({ground, At({0, 0, 0.25 * mm}, Eigen::Quaterniond::Identity())}, {tracked}, &events,
            &stats);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, ContactEvent::Kind::kRemoved);
  EXPECT_EQ(events[0].reason, ContactEvent::Reason::kSeparated);
  stage.Run({ground, At({45 * mm, 0, 0.05 * mm}, Eigen::Quaterniond::Identity())}, {tracked},
            &events, &stats);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].reason, ContactEvent::Reason::kLeftDomain);
  // 1 mm over the floor, untracked: nothing.
  stage.Run({ground, At({0, 0, 1 * mm}, Eigen::Quaterniond::Identity())}, {}, &events, &stats);
  EXPECT_TRUE(events.empty());
  // Without face pairs the stage does not see the pair at all (what FindFaces is for).
  options.face_pairs = false;
  GlobalContactStage blind({{0, &floor, &floor_mesh, nullptr}, {1, &face, &face_mesh, nullptr}},
                           {{0, 1}}, options);
  blind.Run({ground, At({0, 0, 0.05 * mm}, Eigen::Quaterniond::Identity())}, {}, &events, &stats);
  EXPECT_TRUE(events.empty());
}

}  // namespace
}  // namespace tangent::contact
