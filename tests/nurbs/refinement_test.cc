// Refinement never changes the geometry: Oslo refinement, Boehm insertion, Bezier extraction
// and splitting all reproduce the original surface to ≤ 1e-13 over 10^4 samples.

#include "nurbs/refinement.h"

#include <gtest/gtest.h>

#include <random>

#include "testing/random_nurbs.h"

namespace tangent::nurbs {
namespace {

using testing::RandomCurve;
using testing::RandomParam;
using testing::RandomSurface;

// The surfaces have control points of size ≤ ~10; 1e-13 absolute is ~100 ulp of that.
constexpr double kGeomTol = 1e-13;

KnotVector WithExtraKnots(const KnotVector& k, std::mt19937_64& rng, int count) {
  std::vector<double> knots = k.knots();
  for (int i = 0; i < count; ++i) knots.push_back(RandomParam(rng, k));
  // One existing interior knot raised by one, where allowed.
  const double interior = k[k.degree() + 1];
  if (interior > k.domain_begin() && interior < k.domain_end() &&
      k.Multiplicity(interior) < k.degree()) {
    knots.push_back(interior);
  }
  std::sort(knots.begin(), knots.end());
  return KnotVector(k.degree(), std::move(knots));
}

TEST(RefinementTest, OsloRefinementKeepsSurfaceOver10kSamples) {
  std::mt19937_64 rng(42);
  const NurbsSurface s = RandomSurface(rng, 3, 2, 8, 7, true);
  const NurbsSurface r1 = RefineKnots(s, Direction::kU, WithExtraKnots(s.knots_u(), rng, 7));
  const NurbsSurface r = RefineKnots(r1, Direction::kV, WithExtraKnots(s.knots_v(), rng, 5));
  EXPECT_EQ(r.num_u(), s.num_u() + 8);
  double worst = 0.0;
  for (int k = 0; k < 10000; ++k) {
    const double u = RandomParam(rng, s.knots_u()), v = RandomParam(rng, s.knots_v());
    worst =
        std::max(worst, (EvaluateReference(r, u, v, 0).S - EvaluateReference(s, u, v, 0).S).norm());
  }
  EXPECT_LE(worst, kGeomTol);
  RecordProperty("max_deviation", std::to_string(worst));
}

TEST(RefinementTest, OsloAgreesWithBoehmInsertion) {
  std::mt19937_64 rng(43);
  const NurbsCurve<3> c = RandomCurve<3>(rng, 3, 9, true, /*clamped=*/false);
  const double t = RandomParam(rng, c.knots());
  const NurbsCurve<3> boehm = InsertKnot(c, t, 2);
  std::vector<double> knots = c.knots().knots();
  knots.insert(std::upper_bound(knots.begin(), knots.end(), t), 2, t);
  const NurbsCurve<3> oslo = RefineKnots(c, KnotVector(3, knots));
  ASSERT_EQ(boehm.num_points(), oslo.num_points());
  for (int i = 0; i < oslo.num_points(); ++i) {
    EXPECT_LT((boehm.weighted_points()[i] - oslo.weighted_points()[i]).norm(), 1e-13) << i;
  }
  // Surfaces too, in each direction.
  const NurbsSurface s = RandomSurface(rng, 2, 3, 6, 7, true);
  for (Direction dir : {Direction::kU, Direction::kV}) {
    const KnotVector& k = dir == Direction::kU ? s.knots_u() : s.knots_v();
    const double tt = RandomParam(rng, k);
    const NurbsSurface b = InsertKnot(s, dir, tt);
    std::vector<double> kk = k.knots();
    kk.insert(std::upper_bound(kk.begin(), kk.end(), tt), tt);
    const NurbsSurface o = RefineKnots(s, dir, KnotVector(k.degree(), kk));
    for (size_t i = 0; i < o.weighted_points().size(); ++i) {
      EXPECT_LT((b.weighted_points()[i] - o.weighted_points()[i]).norm(), 1e-13);
    }
  }
}

TEST(RefinementTest, BezierExtractionAndSplitKeepGeometry) {
  std::mt19937_64 rng(44);
  const NurbsSurface s = RandomSurface(rng, 3, 3, 7, 6, true, /*clamped=*/false);
  const std::vector<NurbsSurface> patches = ExtractBezier(s);
  const auto bu = s.knots_u().Breakpoints(), bv = s.knots_v().Breakpoints();
  ASSERT_EQ(patches.size(), (bu.size() - 1) * (bv.size() - 1));
  const auto [left, right] = Split(s, Direction::kU, RandomParam(rng, s.knots_u()));
  double worst = 0.0;
  for (int k = 0; k < 10000; ++k) {
    const double u = RandomParam(rng, s.knots_u()), v = RandomParam(rng, s.knots_v());
    const Eigen::Vector3d x = EvaluateReference(s, u, v, 0).S;
    const size_t i =
        static_cast<size_t>(std::upper_bound(bu.begin(), bu.end(), u) - bu.begin() - 1);
    const size_t j =
        static_cast<size_t>(std::upper_bound(bv.begin(), bv.end(), v) - bv.begin() - 1);
    const NurbsSurface& patch =
        patches[std::min(i, bu.size() - 2) * (bv.size() - 1) + std::min(j, bv.size() - 2)];
    worst = std::max(worst, (EvaluateReference(patch, u, v, 0).S - x).norm());
    const NurbsSurface& half = u < left.knots_u().domain_end() ? left : right;
    worst = std::max(worst, (EvaluateReference(half, u, v, 0).S - x).norm());
  }
  EXPECT_LE(worst, kGeomTol);
  EXPECT_TRUE(left.knots_u().IsClamped());
  EXPECT_TRUE(right.knots_u().IsClamped());
}

TEST(RefinementTest, CurveSplitAndExtraction) {
  std::mt19937_64 rng(45);
  const NurbsCurve<2> c = RandomCurve<2>(rng, 4, 10, true);
  const double t = RandomParam(rng, c.knots());
  const auto [a, b] = Split(c, t);
  EXPECT_LT((a.Evaluate(t).C - c.Evaluate(t).C).norm(), kGeomTol);
  EXPECT_LT((b.Evaluate(t).C - c.Evaluate(t).C).norm(), kGeomTol);
  for (const auto& piece : ExtractBezier(c)) {
    const double m = 0.5 * (piece.knots().domain_begin() + piece.knots().domain_end());
    EXPECT_LT((piece.Evaluate(m).C - c.Evaluate(m).C).norm(), kGeomTol);
  }
}

TEST(RefinementTest, RejectsInvalidRequests) {
  std::mt19937_64 rng(46);
  const NurbsCurve<3> c = RandomCurve<3>(rng, 3, 7, false);
  EXPECT_THROW(InsertKnot(c, c.knots().domain_end() + 1.0), std::invalid_argument);
  EXPECT_THROW(InsertKnot(c, RandomParam(rng, c.knots()), 4), std::invalid_argument);
  EXPECT_THROW(Split(c, c.knots().domain_begin()), std::invalid_argument);
  // A "refinement" that drops an interior knot is not one.
  std::vector<double> k = c.knots().knots();
  k.erase(k.begin() + 5);
  k.insert(k.begin() + 5, 0.5 * (k[4] + k[5]));
  try {
    RefineKnots(c, KnotVector(3, k));
    ADD_FAILURE() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contain every interior knot"), std::string::npos);
  }
}

}  // namespace
}  // namespace tangent::nurbs
