// The three evaluation paths (reference basis functions, Oslo refinement, power-basis fast path)
// agree to 1e-12 relative on random rational, non-uniform surfaces and curves of every degree.

#include <gtest/gtest.h>

#include <random>

#include "nurbs/refinement.h"
#include "nurbs/surface.h"
#include "testing/random_nurbs.h"

namespace tangent::nurbs {
namespace {

using testing::RandomCurve;
using testing::RandomParam;
using testing::RandomSurface;

// 1e-12 relative: each path rounds differently (power-basis coefficients amplify rounding by
// the Bernstein-to-monomial conversion, up to ~2^p), so exact equality is not expected; the
// observed worst case over these samples is near 1e-14, well inside.
constexpr double kRelTol = 1e-12;

// Relative error of one derivative family (all partials of one order), scaled by the largest
// of them at that point, so near-zero components are not judged on their own size.
double FamilyError(const SurfacePoint& a, const SurfacePoint& b, int order) {
  auto err = [](std::initializer_list<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs) {
    double scale = 1e-300;
    double diff = 0.0;
    for (const auto& [x, y] : pairs) {
      scale = std::max(scale, y.norm());
      diff = std::max(diff, (x - y).norm());
    }
    return diff / scale;
  };
  if (order == 0) return err({{a.S, b.S}});
  if (order == 1) return err({{a.S_u, b.S_u}, {a.S_v, b.S_v}});
  return err({{a.S_uu, b.S_uu}, {a.S_uv, b.S_uv}, {a.S_vv, b.S_vv}});
}

struct DegreeCase {
  int p, q;
  bool rational, clamped;
};

class SurfacePathsTest : public ::testing::TestWithParam<DegreeCase> {};

TEST_P(SurfacePathsTest, ThreePathsAgree) {
  const DegreeCase c = GetParam();
  std::mt19937_64 rng(1000 + 10 * c.p + c.q + (c.rational ? 500 : 0) + (c.clamped ? 0 : 77));
  double worst[3] = {0, 0, 0};
  for (int surf = 0; surf < 4; ++surf) {
    const NurbsSurface s = RandomSurface(rng, c.p, c.q, c.p + 4, c.q + 5, c.rational, c.clamped);
    SpanHint hint;
    for (int k = 0; k < 200; ++k) {
      double u = RandomParam(rng, s.knots_u());
      double v = RandomParam(rng, s.knots_v());
      if (k == 0) u = s.knots_u().domain_begin();
      if (k == 1) v = s.knots_v().domain_end();
      if (k == 2) u = s.knots_u()[c.p + 1];  // Exactly on an interior knot.
      const SurfacePoint ref = EvaluateReference(s, u, v);
      const SurfacePoint oslo = EvaluateByRefinement(s, u, v);
      SurfacePoint fast;
      s.Evaluate<2>(u, v, &hint, &fast);
      for (int order = 0; order <= 2; ++order) {
        const double e1 = FamilyError(oslo, ref, order);
        const double e2 = FamilyError(fast, ref, order);
        worst[order] = std::max({worst[order], e1, e2});
        ASSERT_LT(e1, kRelTol) << "refinement vs reference, order " << order << " at " << u << ","
                               << v;
        ASSERT_LT(e2, kRelTol) << "fast vs reference, order " << order << " at " << u << "," << v;
      }
    }
  }
  RecordProperty("worst_rel_error_d2", std::to_string(worst[2]));
}

INSTANTIATE_TEST_SUITE_P(
    Degrees, SurfacePathsTest,
    ::testing::Values(DegreeCase{1, 1, false, true}, DegreeCase{1, 2, true, true},
                      DegreeCase{2, 2, true, true}, DegreeCase{3, 3, false, true},
                      DegreeCase{3, 3, true, true}, DegreeCase{3, 3, true, false},
                      DegreeCase{2, 5, true, true}, DegreeCase{4, 4, true, false},
                      DegreeCase{5, 3, true, true}, DegreeCase{7, 6, true, true},
                      DegreeCase{9, 9, true, true}),
    [](const ::testing::TestParamInfo<DegreeCase>& param_info) {
      const DegreeCase& c = param_info.param;
      return "p" + std::to_string(c.p) + "q" + std::to_string(c.q) +
             (c.rational ? "_rational" : "_polynomial") + (c.clamped ? "_clamped" : "_unclamped");
    });

TEST(SurfacePathsTest, LowerOrdersMatchFullEvaluation) {
  std::mt19937_64 rng(7);
  const NurbsSurface s = RandomSurface(rng, 3, 3, 7, 8, true);
  for (int k = 0; k < 50; ++k) {
    const double u = RandomParam(rng, s.knots_u());
    const double v = RandomParam(rng, s.knots_v());
    const SurfacePoint full = s.Evaluate(u, v, 2);
    for (int order = 0; order <= 1; ++order) {
      const SurfacePoint fast = s.Evaluate(u, v, order);
      const SurfacePoint ref = EvaluateReference(s, u, v, order);
      const SurfacePoint oslo = EvaluateByRefinement(s, u, v, order);
      EXPECT_EQ(fast.S, full.S);
      EXPECT_LT((ref.S - full.S).norm(), kRelTol * full.S.norm());
      EXPECT_LT((oslo.S - full.S).norm(), kRelTol * full.S.norm());
      if (order == 1) {
        EXPECT_EQ(fast.S_u, full.S_u);
      }
    }
  }
}

TEST(SurfacePathsTest, SameAnswerOnRepeatedCallsAndAnyHint) {
  std::mt19937_64 rng(8);
  const NurbsSurface s = RandomSurface(rng, 3, 3, 9, 9, true);
  const double u = RandomParam(rng, s.knots_u());
  const double v = RandomParam(rng, s.knots_v());
  SurfacePoint first;
  SpanHint hint;
  s.Evaluate<2>(u, v, &hint, &first);
  for (int h = -3; h < 12; ++h) {
    SpanHint other{h, 11 - h};
    SurfacePoint again;
    s.Evaluate<2>(u, v, &other, &again);
    EXPECT_EQ(again.S, first.S);
    EXPECT_EQ(again.S_uv, first.S_uv);
    EXPECT_EQ(other.u, hint.u);
    EXPECT_EQ(other.v, hint.v);
  }
}

TEST(SurfacePathsTest, OutsideDomainClampsToEdgeInAllPaths) {
  std::mt19937_64 rng(9);
  const NurbsSurface s = RandomSurface(rng, 3, 2, 6, 5, true);
  const double u_end = s.knots_u().domain_end();
  const double v_mid = 0.5 * (s.knots_v().domain_begin() + s.knots_v().domain_end());
  const SurfacePoint edge = EvaluateReference(s, u_end, v_mid);
  EXPECT_LT((s.Evaluate(u_end + 1.0, v_mid).S - edge.S).norm(), 1e-13);
  EXPECT_LT((EvaluateByRefinement(s, u_end + 1.0, v_mid).S - edge.S).norm(), 1e-13);
  EXPECT_LT((EvaluateReference(s, u_end + 1.0, v_mid).S - edge.S).norm(), 1e-13);
}

template <int Dim>
void CheckCurvePaths(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (int p = 1; p <= 9; ++p) {
    for (bool rational : {false, true}) {
      for (bool clamped : {true, false}) {
        const NurbsCurve<Dim> c = RandomCurve<Dim>(rng, p, p + 6, rational, clamped);
        int hint = 0;
        for (int k = 0; k < 100; ++k) {
          const double t = k == 0 ? c.knots().domain_end() : RandomParam(rng, c.knots());
          const CurvePoint<Dim> ref = EvaluateReference(c, t);
          const CurvePoint<Dim> oslo = EvaluateByRefinement(c, t);
          CurvePoint<Dim> fast;
          c.Evaluate(t, 2, &hint, &fast);
          const CurvePoint<Dim>* const both[] = {&oslo, &fast};
          for (const CurvePoint<Dim>* x : both) {
            EXPECT_LT((x->C - ref.C).norm(), kRelTol * std::max(1.0, ref.C.norm())) << p;
            EXPECT_LT((x->C1 - ref.C1).norm(), kRelTol * std::max(1.0, ref.C1.norm())) << p;
            EXPECT_LT((x->C2 - ref.C2).norm(), kRelTol * std::max(1.0, ref.C2.norm())) << p;
          }
        }
      }
    }
  }
}

TEST(CurvePathsTest, ThreePathsAgree2d) { CheckCurvePaths<2>(21); }
TEST(CurvePathsTest, ThreePathsAgree3d) { CheckCurvePaths<3>(31); }

// Derivatives of the fast path against central differences of the fast path itself: a check
// independent of the basis-derivative recurrences. h = 1e-5 gives truncation O(h²|S'''|) ~ 1e-10
// and rounding O(eps/h) ~ 1e-11 for first derivatives; second derivatives of S' lose one more h.
TEST(SurfacePathsTest, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(11);
  const NurbsSurface s = RandomSurface(rng, 3, 3, 6, 6, true);
  const double h = 1e-5;
  for (int k = 0; k < 50; ++k) {
    // Keep away from knots so the difference stencil stays on one polynomial piece... or on a
    // C² join for cubics, where differences remain valid.
    const double u = RandomParam(rng, s.knots_u());
    const double v = RandomParam(rng, s.knots_v());
    if (u - h < s.knots_u().domain_begin() || u + h > s.knots_u().domain_end()) continue;
    if (v - h < s.knots_v().domain_begin() || v + h > s.knots_v().domain_end()) continue;
    const SurfacePoint c = s.Evaluate(u, v);
    const SurfacePoint up = s.Evaluate(u + h, v), um = s.Evaluate(u - h, v);
    const SurfacePoint vp = s.Evaluate(u, v + h), vm = s.Evaluate(u, v - h);
    const double tol1 = 1e-7 * std::max(1.0, c.S_u.norm() + c.S_v.norm());
    const double tol2 = 1e-6 * std::max(1.0, c.S_uu.norm() + c.S_uv.norm() + c.S_vv.norm());
    EXPECT_LT(((up.S - um.S) / (2 * h) - c.S_u).norm(), tol1);
    EXPECT_LT(((vp.S - vm.S) / (2 * h) - c.S_v).norm(), tol1);
    EXPECT_LT(((up.S_u - um.S_u) / (2 * h) - c.S_uu).norm(), tol2);
    EXPECT_LT(((vp.S_u - vm.S_u) / (2 * h) - c.S_uv).norm(), tol2);
    EXPECT_LT(((up.S_v - um.S_v) / (2 * h) - c.S_uv).norm(), tol2);
    EXPECT_LT(((vp.S_v - vm.S_v) / (2 * h) - c.S_vv).norm(), tol2);
  }
}

}  // namespace
}  // namespace tangent::nurbs
