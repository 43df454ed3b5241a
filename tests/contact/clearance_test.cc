// The clearance certificate (contact/clearance.h): a lower bound on the distance between two
// watched surfaces, against distances known in closed form (spheres, a sphere over a plane)
// and dense samples of random rational sheets; reused after a move only as far as the move
// allows; and the body pairs a scene's declarations watch.

#include "contact/clearance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>

#include "nurbs/primitives.h"
#include "testing/random_nurbs.h"

namespace tangent::contact {
namespace {

BodyPose Pose(const Eigen::Vector3d& p,
              const Eigen::Quaterniond& Q = Eigen::Quaterniond::Identity()) {
  Vector7d q;
  q << p, Q.w(), Q.x(), Q.y(), Q.z();
  return BodyPose::FromCoordinates(q);
}

nurbs::NurbsSurface Scaled(const nurbs::NurbsSurface& s, double k) {
  std::vector<Eigen::Vector4d> cpw = s.weighted_points();
  for (Eigen::Vector4d& h : cpw) h.head<3>() *= k;
  return nurbs::NurbsSurface::FromHomogeneous(s.knots_u(), s.knots_v(), std::move(cpw));
}

// The smallest distance between n × n samples of each surface (≥ the true distance).
double SampledDistance(const nurbs::NurbsSurface& f, const BodyPose& pf,
                       const nurbs::NurbsSurface& g, const BodyPose& pg, int n) {
  auto samples = [n](const nurbs::NurbsSurface& s, const BodyPose& p) {
    std::vector<Eigen::Vector3d> x;
    const auto& ku = s.knots_u();
    const auto& kv = s.knots_v();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double u = ku.domain_begin() + (ku.domain_end() - ku.domain_begin()) * i / (n - 1);
        const double v = kv.domain_begin() + (kv.domain_end() - kv.domain_begin()) * j / (n - 1);
        x.push_back(p.Point(s.Evaluate(u, v, 0).S));
      }
    }
    return x;
  };
  const auto a = samples(f, pf), b = samples(g, pg);
  double d = std::numeric_limits<double>::infinity();
  for (const auto& x : a) {
    for (const auto& y : b) d = std::min(d, (x - y).squaredNorm());
  }
  return std::sqrt(d);
}

TEST(ClearanceTest, TwoSpheresAtKnownDistances) {
  // Coarse tessellations (ε = 0.2 mm on 5 mm spheres): chords lie inside a sphere, so the meshes
  // are farther apart than the spheres; the bound must take both ε off.
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 5e-3);
  const nurbs::OffsetMesh mesh = nurbs::MakeOffsetMesh(ball, 2e-4, 1e-4);
  ASSERT_GT(mesh.base.error_bound, 0.0);
  std::vector<GlobalSurface> surfaces = {{0, &ball, &mesh, nullptr}, {1, &ball, &mesh, nullptr}};
  ClearanceCertifier certifier(surfaces, {{0, 1}}, {}, 0.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int tight = 0;
  for (double gap : {1e-5, 1e-4, 1e-3, 3e-3, 2e-2}) {
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d dir = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
      const Eigen::Quaterniond Q =
          Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
      const std::vector<BodyPose> poses = {Pose(Eigen::Vector3d::Zero(), Q),
                                           Pose((10e-3 + gap) * dir)};
      const double c = certifier.SurfaceClearance(0, 1, poses);
      EXPECT_LE(c, gap) << "gap " << gap;
      EXPECT_GE(c, gap - 2.0 * mesh.base.error_bound - 1e-12) << "gap " << gap;
      tight += c > gap - 2.0 * mesh.base.error_bound;
    }
  }
  EXPECT_GT(tight, 0);
}

TEST(ClearanceTest, ASphereOverAPlaneAndRandomSheets) {
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 5e-3);
  const nurbs::NurbsSurface plane = nurbs::MakePlanePatch(
      Eigen::Vector3d(-0.02, -0.02, 0), Eigen::Vector3d(0.04, 0, 0), Eigen::Vector3d(0, 0.04, 0));
  const nurbs::OffsetMesh mb = nurbs::MakeOffsetMesh(ball, 2e-5, 2.5e-4);
  const nurbs::OffsetMesh mp = nurbs::MakeOffsetMesh(plane, 2e-5, 2.5e-4);
  std::vector<GlobalSurface> surfaces = {{0, &plane, &mp, nullptr}, {1, &ball, &mb, nullptr}};
  ClearanceCertifier certifier(surfaces, {{0, 1}}, {}, 0.0);
  for (double h : {5.0005e-3, 5.01e-3, 5.3e-3, 8e-3}) {
    const std::vector<BodyPose> poses = {Pose(Eigen::Vector3d::Zero()),
                                         Pose(Eigen::Vector3d(1e-3, -2e-3, h))};
    const double c = certifier.SurfaceClearance(0, 1, poses);
    EXPECT_LE(c, h - 5e-3);
    EXPECT_GE(c, h - 5e-3 - 2.0 * (mb.base.error_bound + mp.base.error_bound));
  }
  // Random rational sheets (about 4 x 4 units, scaled to centimetres) over one another.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    const nurbs::NurbsSurface f =
        Scaled(nurbs::testing::RandomSurface(rng, 3, 3, 5, 5, true), 5e-3);
    const nurbs::NurbsSurface g =
        Scaled(nurbs::testing::RandomSurface(rng, 2, 3, 4, 5, true), 5e-3);
    const nurbs::OffsetMesh mf = nurbs::MakeOffsetMesh(f, 2e-5, 2.5e-4);
    const nurbs::OffsetMesh mg = nurbs::MakeOffsetMesh(g, 2e-5, 2.5e-4);
    std::vector<GlobalSurface> s = {{0, &f, &mf, nullptr}, {1, &g, &mg, nullptr}};
    // Measured by the tessellations however far apart (not by the bounding spheres' gap).
    ClearanceCertifier sheets(s, {{0, 1}}, {}, 0.0, std::numeric_limits<double>::infinity());
    const Eigen::Quaterniond Q =
        Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
    const std::vector<BodyPose> poses = {
        Pose(Eigen::Vector3d::Zero()), Pose(Eigen::Vector3d(unit(rng), unit(rng), 4.0) * 5e-3, Q)};
    const double sampled = SampledDistance(f, poses[0], g, poses[1], 120);
    const double c = sheets.SurfaceClearance(0, 1, poses);
    EXPECT_LE(c, sampled) << "trial " << trial;
    // Sample spacing: ≤ about 1/119 of a 2.5 cm sheet's side on each surface.
    EXPECT_GE(c, sampled - 2.0 * (mf.base.error_bound + mg.base.error_bound) - 2 * 3e-4)
        << "trial " << trial;
  }
}

TEST(ClearanceTest, AMeasurementIsReusedOnlyAsFarAsTheMoveAllows) {
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 5e-3);
  const nurbs::OffsetMesh mesh = nurbs::MakeOffsetMesh(ball, 2e-5, 2.5e-4);
  std::vector<GlobalSurface> surfaces = {{0, &ball, &mesh, nullptr}, {1, &ball, &mesh, nullptr}};
  ClearanceCertifier certifier(surfaces, {{0, 1}}, {}, 0.0);
  // Measured 4 mm apart, then the second sphere walks toward the first and turns: every bound
  // stays below the true gap, reused or measured again.
  double gap = 4e-3;
  for (int k = 0; k < 40; ++k, gap *= 0.9) {
    const Eigen::Quaterniond Q(Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d::UnitY()));
    const std::vector<BodyPose> poses = {Pose(Eigen::Vector3d::Zero()),
                                         Pose(Eigen::Vector3d(10e-3 + gap, 0, 0), Q)};
    const double c = certifier.SurfaceClearance(0, 1, poses);
    EXPECT_LE(c, gap) << "step " << k;
    EXPECT_GE(c, 0.7 * gap - 2.0 * mesh.base.error_bound) << "step " << k;
  }
}

TEST(ClearanceTest, BuildAllBuildsWhatTheDeclarationsCanMeasureAndChangesNoCertificate) {
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 5e-3);
  const nurbs::OffsetMesh mesh = nurbs::MakeOffsetMesh(ball, 2e-5, 2.5e-4);
  // Bodies 0..3: surfaces 0 and 1 declared as a pair; body pair (2, 0) as a whole; surface 3 on
  // body 3 with a mesh but in no pair, and surface 4 on body 1 without a mesh.
  std::vector<GlobalSurface> surfaces = {{0, &ball, &mesh, nullptr},
                                         {1, &ball, &mesh, nullptr},
                                         {2, &ball, &mesh, nullptr},
                                         {3, &ball, &mesh, nullptr},
                                         {1, &ball, nullptr, nullptr}};
  const std::vector<std::pair<int, int>> pairs = {{0, 1}};
  const std::vector<std::pair<int, int>> body_pairs = {{2, 0}};
  const std::vector<BodyPose> poses = {
      Pose(Eigen::Vector3d::Zero()), Pose(Eigen::Vector3d(10.5e-3, 0, 0)),
      Pose(Eigen::Vector3d(0, 10.4e-3, 0)), Pose(Eigen::Vector3d(0, 0, 0.1))};
  ClearanceCertifier lazy(surfaces, pairs, body_pairs, 5e-5);
  ClearanceCertifier eager(surfaces, pairs, body_pairs, 5e-5);
  EXPECT_EQ(eager.BuildAll(), 3);  // surfaces 0, 1 and 2: not 3 (no pair), not 4 (no mesh)
  EXPECT_EQ(eager.BuildAll(), 0);  // built once
  std::vector<double> a, b;
  lazy.Certify(poses, {}, {}, &a);
  eager.Certify(poses, {}, {}, &b);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a, b);
  EXPECT_LT(a[0], 0.5e-3);  // measured on the tessellations (within exact_within)
  EXPECT_LT(a[1], 0.4e-3);
  EXPECT_EQ(lazy.BuildAll(), 0);  // Certify built the same three on first use
}

TEST(ClearanceTest, CertifyLeavesOutContactsAndTakesTheStagesView) {
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 5e-3);
  const nurbs::OffsetMesh mesh = nurbs::MakeOffsetMesh(ball, 2e-5, 2.5e-4);
  // Three balls on bodies 0, 1, 2; surface pairs (0, 1), (1, 2) declared, body pair (0, 2).
  std::vector<GlobalSurface> surfaces = {
      {0, &ball, &mesh, nullptr}, {1, &ball, &mesh, nullptr}, {2, &ball, &mesh, nullptr}};
  const std::vector<std::pair<int, int>> pairs = {{1, 0}, {1, 2}};
  const std::vector<std::pair<int, int>> body_pairs = {{2, 0}};
  EXPECT_EQ(WatchedBodyPairs(surfaces, pairs, body_pairs),
            (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}, {1, 2}}));
  const double standoff = 5e-5;
  ClearanceCertifier certifier(surfaces, pairs, body_pairs, standoff);
  const std::vector<BodyPose> poses = {Pose(Eigen::Vector3d::Zero()),
                                       Pose(Eigen::Vector3d(12e-3, 0, 0)),
                                       Pose(Eigen::Vector3d(0, 10.02e-3, 0))};
  std::vector<double> c;
  certifier.Certify(poses, {}, {}, &c);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_NEAR(c[0], 2e-3 - standoff, 1e-4);  // (0, 1) 2 mm apart
  // (0, 2) 0.02 mm apart: nearer than the standoff, not certified.
  EXPECT_EQ(c[1], std::numeric_limits<double>::infinity());
  // Nor at 0.08 mm, within twice the standoff (the stage's activation distance: its contact).
  std::vector<BodyPose> within = poses;
  within[2] = Pose(Eigen::Vector3d(0, 10.08e-3, 0));
  certifier.Certify(within, {}, {}, &c);
  EXPECT_EQ(c[1], std::numeric_limits<double>::infinity());
  within[2] = Pose(Eigen::Vector3d(0, 10.15e-3, 0));
  certifier.Certify(within, {}, {}, &c);
  EXPECT_LT(c[1], 1.5e-4 - standoff);
  EXPECT_GE(c[1], 1.5e-4 - standoff - 2.0 * mesh.base.error_bound - 1e-12);
  certifier.Certify(poses, {}, {}, &c);
  EXPECT_GT(c[2], 0.0);
  // In contact: left out.
  certifier.Certify(poses, {{0, 1}}, {}, &c);
  EXPECT_EQ(c[0], std::numeric_limits<double>::infinity());
  // In the stage's view (balls 0 and 1 now 0.2 mm apart): the refinements' distance on the
  // material when it is more than the tessellations say (a trimmed face's uncut cells reach past
  // its trim), capped by the offsets' reach; the tessellations' own bound otherwise.
  const std::vector<BodyPose> near = {Pose(Eigen::Vector3d::Zero()),
                                      Pose(Eigen::Vector3d(10.2e-3, 0, 0)), poses[2]};
  certifier.Certify(near, {}, {}, &c);
  const double strict = c[0];
  EXPECT_LE(strict, 2e-4 - standoff);
  EXPECT_GE(strict, 2e-4 - standoff - 2.0 * mesh.base.error_bound);
  certifier.Certify(near, {}, {{0, 1, 3e-4}}, &c);
  EXPECT_DOUBLE_EQ(c[0], 3e-4 - standoff);
  certifier.Certify(near, {}, {{0, 1, 1.0}}, &c);
  EXPECT_DOUBLE_EQ(c[0], 2.0 * mesh.offset - 4.0 * mesh.base.error_bound - standoff);
  certifier.Certify(near, {}, {{0, 1, 1e-4}}, &c);
  EXPECT_DOUBLE_EQ(c[0], strict);
  // No refinement converged to a minimum (parallel planes' continuum): the tessellations' bound.
  certifier.Certify(near, {}, {{0, 1, std::numeric_limits<double>::infinity()}}, &c);
  EXPECT_DOUBLE_EQ(c[0], strict);
  // Where the tessellations may meet, a refinement can converge beside the crossing (a tilted
  // face through a plane, its corner apart): nothing is certified, whatever it measured.
  const std::vector<BodyPose> crossing = {Pose(Eigen::Vector3d::Zero()),
                                          Pose(Eigen::Vector3d(9.9e-3, 0, 0)), poses[2]};
  certifier.Certify(crossing, {}, {{0, 1, 1e-3}}, &c);
  EXPECT_EQ(c[0], std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace tangent::contact
