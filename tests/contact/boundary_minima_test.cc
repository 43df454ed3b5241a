// Minima on the domain boundary: edge–edge, corner–face and edge–face configurations of random
// rational patches, a point beside a patch and a curve past one, each against a dense-sampling
// truth that knows nothing of our solvers. Every seed the docs promise (the closest sample, any
// seed within the stated basin, the minimum itself) must reach the sampled global minimum; the
// rate from uniformly random seeds is printed, not asserted (a random seed may belong to another
// local minimum).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "testing/boundary_cases.h"
#include "testing/random_nurbs.h"

namespace tangent::contact {
namespace {

using nurbs::NurbsSurface;
using nurbs::testing::RandomSurface;
using testing::Case;
using testing::Hi;
using testing::Layout;
using testing::Lo;
using testing::Place;
using testing::PoseCoordinates;
using testing::SampledClosestPair;
using testing::Sheet;
using testing::Truth;

// The sampled truth is within this of the true minimum: the fine window's spacing in space is
// ~4/64·4/40 ≈ 6e-3, and the distance is quadratic in it along free directions (curvature ~1
// per unit), linear only along a held one, whose samples lie on the bound exactly.
constexpr double kSampleSlack = 2e-4;

bool AnyHeld(const std::array<bool, 4>& a) { return a[0] || a[1] || a[2] || a[3]; }
std::string Category(const std::array<bool, 4>& a) {
  const int nf = a[0] + a[1], ng = a[2] + a[3];
  auto part = [](int n) { return n == 0 ? "face" : n == 1 ? "edge" : "corner"; };
  return std::string(part(nf)) + "-" + part(ng);
}

Case MakeCase(std::mt19937_64& rng, Layout layout) {
  NurbsSurface f = RandomSurface(rng, 3, 3, 5, 5, true);
  NurbsSurface g = RandomSurface(rng, 3, 3, 5, 5, true);
  return Place(rng, layout, std::move(f), std::move(g));
}

// A solve reached the sampled global minimum: a minimum by its own test, no further than the
// sampled distance (which bounds the true minimum from above), and β the distance between the
// points, positive (apart), at a boundary extremum.
::testing::AssertionResult ReachedMinimum(const SurfaceSurfaceExtremum& e, const Truth& t) {
  const double dist = (e.p_f - e.p_g).norm();
  if (e.status != ExtremalStatus::kConverged && e.status != ExtremalStatus::kAtBoundary)
    return ::testing::AssertionFailure() << "status " << ToString(e.status);
  if (e.kind != ExtremumKind::kMinimum)
    return ::testing::AssertionFailure() << "kind " << ToString(e.kind);
  if (dist > t.distance + 1e-12)
    return ::testing::AssertionFailure()
           << "distance " << dist << " above the sampled minimum " << t.distance;
  if (dist < t.distance - kSampleSlack)
    return ::testing::AssertionFailure()
           << "sampled truth too coarse: " << dist << " vs " << t.distance;
  // Random sheets are not oriented as facing solids: the side follows BoundarySide's rule.
  const double side = BoundarySide(e.p_f - e.p_g, e.R_WCf.col(2), e.R_WCg.col(2));
  if (AnyHeld(e.at_bound) && std::abs(e.beta - side * dist) > 1e-12 * std::max(1.0, dist))
    return ::testing::AssertionFailure() << "beta " << e.beta << " is not the distance " << dist
                                         << " signed by the side " << side;
  return ::testing::AssertionSuccess();
}

// A seed within `radius` (a fraction of each domain width) of u, clamped into the domains.
Eigen::Vector4d Near(std::mt19937_64& rng, const Eigen::Vector4d& u, const Eigen::Vector4d& lo,
                     const Eigen::Vector4d& hi, double radius) {
  std::uniform_real_distribution<double> d(-radius, radius);
  Eigen::Vector4d s;
  for (int i = 0; i < 4; ++i) s[i] = std::clamp(u[i] + d(rng) * (hi[i] - lo[i]), lo[i], hi[i]);
  return s;
}

// The basin docs/stability.md states: seeds within 2 % of each domain width of the minimum.
constexpr double kBasin = 0.02;

TEST(BoundaryMinimaTest, RandomRationalPatchesFromManySeeds) {
  std::mt19937_64 rng(20261201);
  struct Tally {
    int cases = 0, sample_ok = 0, basin = 0, basin_ok = 0, at_min_ok = 0, random = 0, random_ok = 0;
  };
  std::map<std::string, Tally> by_category;
  const char* names[] = {"corner-face layout", "edge-face layout", "edge-edge layout"};
  for (Layout layout : {Layout::kCornerFace, Layout::kEdgeFace, Layout::kEdgeEdge}) {
    for (int k = 0; k < 8; ++k) {
      const Case c = MakeCase(rng, layout);
      const Truth truth = SampledClosestPair(c.f, c.pf, c.g, c.pg);
      Eigen::Vector4d lo, hi;
      lo << Lo(c.f), Lo(c.g);
      hi << Hi(c.f), Hi(c.g);
      const SurfaceSurfaceExtremum global =
          SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, ClosestSamplePair(c.f, c.pf, c.g, c.pg, 16));
      ASSERT_TRUE(ReachedMinimum(global, truth))
          << names[static_cast<int>(layout)] << " case " << k;
      const std::string cat = Category(global.at_bound);
      Tally& t = by_category[cat];
      ++t.cases;
      ++t.sample_ok;
      // Seeded exactly at the minimum: it stays.
      const SurfaceSurfaceExtremum again = SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, global.u);
      EXPECT_TRUE(ReachedMinimum(again, truth)) << cat << " case " << k << " (seed at the minimum)";
      EXPECT_LT((again.u - global.u).cwiseQuotient(hi - lo).cwiseAbs().maxCoeff(), 1e-9);
      t.at_min_ok += ReachedMinimum(again, truth);
      for (int s = 0; s < 20; ++s) {
        const SurfaceSurfaceExtremum e =
            SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, Near(rng, global.u, lo, hi, kBasin));
        ++t.basin;
        const bool ok = ReachedMinimum(e, truth) && std::abs(e.beta - global.beta) < 1e-11;
        t.basin_ok += ok;
        EXPECT_TRUE(ok) << cat << " case " << k << " basin seed " << s << ": beta " << e.beta
                        << " vs " << global.beta << " " << ToString(e.status) << " "
                        << ToString(e.kind) << "\n u " << e.u.transpose() << "\n min "
                        << global.u.transpose() << "\n lo " << lo.transpose() << " hi "
                        << hi.transpose() << " held " << e.at_bound[0] << e.at_bound[1]
                        << e.at_bound[2] << e.at_bound[3] << " vs " << Category(global.at_bound);
      }
      for (int s = 0; s < 20; ++s) {
        Eigen::Vector4d seed;
        for (int i = 0; i < 4; ++i)
          seed[i] = std::uniform_real_distribution<double>(lo[i], hi[i])(rng);
        const SurfaceSurfaceExtremum e = SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, seed);
        ++t.random;
        t.random_ok += ReachedMinimum(e, truth) && std::abs(e.beta - global.beta) < 1e-11;
      }
      if (AnyHeld(global.at_bound)) {
        // β at an edge or corner extremum is the distance between the points (ReachedMinimum),
        // measured along the direction it reports.
        EXPECT_NEAR(global.direction.dot(global.p_f - global.p_g), global.beta, 1e-12);
      }
    }
  }
  std::printf("%-14s %5s %14s %14s %16s %14s\n", "minimum", "cases", "closest sample",
              "at the minimum", "within 2 % basin", "random seeds");
  for (const auto& [cat, t] : by_category) {
    std::printf("%-14s %5d %9d/%-4d %9d/%-4d %11d/%-4d %9d/%-4d\n", cat.c_str(), t.cases,
                t.sample_ok, t.cases, t.at_min_ok, t.cases, t.basin_ok, t.basin, t.random_ok,
                t.random);
  }
  // The layouts must produce boundary minima of each kind the issue names.
  EXPECT_GE(by_category.size(), 3u);
}

// Issue 38: the closest sample of a grid can lie in the basin of another local minimum when the
// global one is on an edge or a corner (a random bicubic pair ended at 1.0107 for 1.0094).
// ClosestSamplePair solves the edges and corners as curve–surface and point–surface problems
// of their own, so the solve from its seed reaches the sampled global minimum: on random pairs
// of degree 1 to 7, rational and not, in the three boundary layouts. A seed within 5 % of the
// domain widths of the minimum can lie beyond a barrier, in the basin of a corner; the solver's
// neighbourhood search (ExtremalOptions::neighbourhood, ±10 %) reaches the minimum from every
// one. Without it (kContinuation) some miss: the cases are hard enough to need it.
TEST(BoundaryMinimaTest, TheClosestSampleSeedReachesTheGlobalMinimumAtEveryDegree) {
  std::mt19937_64 rng(38);
  int cases = 0, reached = 0, on_boundary = 0, near = 0, near_ok = 0, missed_alone = 0;
  double worst = -std::numeric_limits<double>::infinity(), near_worst = worst;
  for (int degree = 1; degree <= 7; ++degree) {
    for (Layout layout : {Layout::kCornerFace, Layout::kEdgeFace, Layout::kEdgeEdge}) {
      for (int k = 0; k < 3; ++k) {
        const bool rational = (degree + k) % 2 == 0;
        NurbsSurface f = Sheet(rng, degree, rational);
        NurbsSurface g = Sheet(rng, degree, !rational);
        const Case c = Place(rng, layout, std::move(f), std::move(g));
        const Truth truth = SampledClosestPair(c.f, c.pf, c.g, c.pg);
        const SurfaceSurfaceExtremum e =
            SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, ClosestSamplePair(c.f, c.pf, c.g, c.pg, 16));
        ++cases;
        const bool ok = ReachedMinimum(e, truth);
        reached += ok;
        on_boundary += AnyHeld(e.at_bound);
        worst = std::max(worst, (e.p_f - e.p_g).norm() - truth.distance);
        EXPECT_TRUE(ok) << "degree " << degree << (rational ? " rational f" : " rational g")
                        << " layout " << static_cast<int>(layout) << " case " << k << ": "
                        << (e.p_f - e.p_g).norm() << " vs sampled " << truth.distance << " "
                        << ToString(e.status) << " " << ToString(e.kind);
        Eigen::Vector4d lo, hi;
        lo << Lo(c.f), Lo(c.g);
        hi << Hi(c.f), Hi(c.g);
        for (int s = 0; s < 5; ++s) {
          const Eigen::Vector4d seed = Near(rng, e.u, lo, hi, 0.05);
          const SurfaceSurfaceExtremum n = SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, seed);
          ++near;
          near_ok += ReachedMinimum(n, truth);
          EXPECT_TRUE(ReachedMinimum(n, truth))
              << "degree " << degree << " layout " << static_cast<int>(layout) << " case " << k
              << " seed " << seed.transpose();
          near_worst = std::max(near_worst, (n.p_f - n.p_g).norm() - truth.distance);
          const SurfaceSurfaceExtremum alone =
              SolveSurfaceSurface(c.f, c.pf, c.g, c.pg, seed, kContinuation);
          missed_alone += !ReachedMinimum(alone, truth);
        }
      }
    }
  }
  std::printf(
      "closest-sample seeds, degrees 1-7: %d of %d reached the sampled global minimum (%d on "
      "an edge or corner; worst gap %.2g m, negative: below the sampled bound); seeds within "
      "5 %% of it: %d of %d (worst gap %.2g m); without the neighbourhood search %d missed\n",
      reached, cases, on_boundary, worst, near_ok, near, near_worst, missed_alone);
  EXPECT_GE(on_boundary, cases / 2);  // the layouts make boundary minima
  EXPECT_GT(missed_alone, 0);         // the seeds are ones a local descent alone can miss
}

// Corner of one flat sheet against the edge of another, in closed form: f is the unit square
// in z = 1 turned 45° about z (its corner at the origin's side), g the square [1, 2] x [0, 1]
// in z = 0: the closest points are f's corner (0.5, 0.5 − √2/2·…) — computed below — and g's
// edge x = 1, both held.
TEST(BoundaryMinimaTest, CornerAgainstEdgeOfFlatSheetsIsTheEuclideanDistance) {
  const NurbsSurface f = nurbs::MakePlanePatch({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const NurbsSurface g = nurbs::MakePlanePatch({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  // f: the unit square turned 45° about z, its right corner at (0, 0.5, 1).
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d corner_right = turn * Eigen::Vector3d(1, 0, 0);  // f(1, 0) from f(0, 0)
  const Eigen::Vector3d origin = Eigen::Vector3d(0, 0.5, 1) - corner_right;
  const BodyPose pf = BodyPose::FromCoordinates(PoseCoordinates(origin, turn));
  const BodyPose pg =
      BodyPose::FromCoordinates(PoseCoordinates({1, 0, 0}, Eigen::Quaterniond::Identity()));
  // f's corner (0, 0.5, 1) against g's edge x = 1 (from (1, 0, 0) to (1, 1, 0)): (1, 0.5, 0).
  const double expected = std::sqrt(2.0);
  for (const Eigen::Vector4d& seed :
       {ClosestSamplePair(f, pf, g, pg, 16), Eigen::Vector4d(0.5, 0.5, 0.5, 0.5),
        Eigen::Vector4d(0.9, 0.1, 0.2, 0.3), Eigen::Vector4d(0.98, 0.02, 0.0, 0.5)}) {
    const SurfaceSurfaceExtremum e = SolveSurfaceSurface(f, pf, g, pg, seed);
    EXPECT_EQ(e.status, ExtremalStatus::kAtBoundary) << ToString(e.status);
    EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
    EXPECT_NEAR(e.beta, expected, 1e-14) << "seed " << seed.transpose();
    EXPECT_LT((e.p_f - Eigen::Vector3d(0, 0.5, 1)).norm(), 1e-13);
    EXPECT_LT((e.p_g - Eigen::Vector3d(1, 0.5, 0)).norm(), 1e-13);
    EXPECT_TRUE(e.at_bound[0] && e.at_bound[1] && e.at_bound[2] && !e.at_bound[3]);
  }
}

// A point beside a patch (nearest point on an edge or a corner) and a curve passing it.
TEST(BoundaryMinimaTest, PointBesideAndCurvePastARandomPatch) {
  std::mt19937_64 rng(7);
  const BodyPose id =
      BodyPose::FromCoordinates(PoseCoordinates({0, 0, 0}, Eigen::Quaterniond::Identity()));
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int edge = 0, corner = 0;
  for (int k = 0; k < 30; ++k) {
    const NurbsSurface s = RandomSurface(rng, 3, 2, 5, 4, true);
    // Outside the footprint [0, 4] x [0, 3] in x and/or y.
    const Eigen::Vector3d x(k % 3 == 0 ? 1.0 + 2 * uni(rng) : 4.5 + uni(rng),
                            k % 3 == 1 ? 1.0 + uni(rng) : -0.5 - uni(rng), uni(rng) - 0.5);
    // Truth: a 400² sampling of the domain (edges included).
    const Eigen::Vector2d lo = Lo(s), hi = Hi(s);
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d best_u;
    constexpr int n = 400;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const Eigen::Vector2d uv = lo + (hi - lo).cwiseProduct(Eigen::Vector2d(i, j) / n);
        const double d = (s.Evaluate(uv[0], uv[1], 0).S - x).norm();
        if (d < best) best = d, best_u = uv;
      }
    }
    for (const Eigen::Vector2d& seed :
         {Eigen::Vector2d(0.5 * (lo + hi)), best_u,
          Eigen::Vector2d((best_u + 0.05 * (hi - lo)).cwiseMin(hi))}) {
      const PointSurfaceExtremum e = SolvePointSurface(x, s, id, seed);
      const double dist = (e.p_f - x).norm();
      ASSERT_TRUE(e.status == ExtremalStatus::kAtBoundary || e.status == ExtremalStatus::kConverged)
          << ToString(e.status);
      EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
      EXPECT_LE(dist, best + 1e-12) << "case " << k;
      EXPECT_GT(dist, best - 1e-4);
      EXPECT_NEAR(std::abs(e.distance), dist, 1e-12);
      if (seed == best_u) {
        edge += e.at_bound[0] != e.at_bound[1];
        corner += e.at_bound[0] && e.at_bound[1];
      }
    }
  }
  std::printf("point beside a patch: %d edge and %d corner minima of 30, all from 3 seeds\n", edge,
              corner);
  EXPECT_GT(edge, 0);
  EXPECT_GT(corner, 0);

  // A curve ending beside a patch: its end point against the patch's edge.
  int curve_cases = 0;
  for (int k = 0; k < 10; ++k) {
    const NurbsSurface s = RandomSurface(rng, 3, 3, 5, 5, true);
    std::vector<Eigen::Vector3d> pts = {
        {5.0 + uni(rng), 1.0, 1.0}, {6.0, 2.0, 0.5 + uni(rng)}, {7.0, 1.5 + uni(rng), 2.0}};
    const nurbs::NurbsCurve3d c(nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}), pts);
    const BodyCurve bc(&c);
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 200; ++i) {
      const Eigen::Vector3d y = c.Evaluate(i / 200.0, 0).C;
      for (int a = 0; a <= 200; ++a) {
        for (int b = 0; b <= 200; ++b) {
          const Eigen::Vector2d uv =
              Lo(s) + (Hi(s) - Lo(s)).cwiseProduct(Eigen::Vector2d(a, b) / 200);
          best = std::min(best, (s.Evaluate(uv[0], uv[1], 0).S - y).norm());
        }
      }
    }
    const Eigen::Vector3d seed(0.5 * (Lo(s)[0] + Hi(s)[0]), 0.5 * (Lo(s)[1] + Hi(s)[1]), 0.5);
    const CurveSurfaceExtremum e = SolveCurveSurface(s, id, bc, id, seed);
    const double dist = (e.p_f - e.p_g).norm();
    EXPECT_EQ(e.kind, ExtremumKind::kMinimum) << "curve case " << k;
    EXPECT_LE(dist, best + 1e-12) << "curve case " << k;
    EXPECT_GT(dist, best - 2e-3);
    EXPECT_NEAR(std::abs(e.beta), dist, 1e-12);
    curve_cases += e.at_bound[2];
  }
  std::printf("curve past a patch: %d of 10 minima at the curve's end\n", curve_cases);
  EXPECT_GT(curve_cases, 0);
}

}  // namespace
}  // namespace tangent::contact
