// The servo-loop evaluators never touch the heap: every global operator new is counted while
// they run (testing/alloc_counter.cc; it catches std::vector, Eigen dynamic types and
// anything else routed through the C++ allocator).

#include <gtest/gtest.h>

#include <random>

#include "nurbs/curve.h"
#include "nurbs/primitives.h"
#include "nurbs/surface.h"
#include "testing/alloc_counter.h"
#include "testing/random_nurbs.h"

namespace tangent::nurbs {
namespace {

TEST(NoAllocationTest, CounterSeesAllocations) {
  const long before = tangent::testing::AllocationCount();
  auto* v = new std::vector<double>(100);
  (*v)[3] = 1.0;
  volatile double sink = (*v)[3];
  (void)sink;
  delete v;
  // The counter is live (the compiler may merge the vector's two allocations, so at least one).
  EXPECT_GE(tangent::testing::AllocationCount() - before, 1);
}

TEST(NoAllocationTest, FastSurfaceAndCurveEvaluationDoNotAllocate) {
  std::mt19937_64 rng(17);
  const NurbsSurface bicubic = testing::RandomSurface(rng, 3, 3, 9, 9, true);
  const NurbsSurface high = testing::RandomSurface(rng, 5, 4, 8, 8, true);
  const NurbsSurface clip = MakeTube(PaperclipPath(), kPaperclipWireRadius);
  const NurbsCurve<2> trim = testing::RandomCurve<2>(rng, 3, 8, true);
  std::vector<double> us(1000), vs(1000);
  for (size_t i = 0; i < us.size(); ++i) {
    us[i] = std::uniform_real_distribution<double>(-1, 5)(rng);  // Also outside the domains.
    vs[i] = std::uniform_real_distribution<double>(-1, 5)(rng);
  }
  SpanHint h1, h2, h3;
  int curve_hint = 0;
  SurfacePoint out;
  CurvePoint<2> cout;
  double sink = 0.0;
  const long before = tangent::testing::AllocationCount();
  for (size_t i = 0; i < us.size(); ++i) {
    bicubic.Evaluate<2>(us[i], vs[i], &h1, &out);
    sink += out.S_uv.x();
    high.Evaluate<1>(us[i], vs[i], &h2, &out);
    sink += out.S_u.y();
    clip.Evaluate<0>(us[i], vs[i], &h3, &out);
    sink += out.S.z();
    trim.Evaluate(us[i], 2, &curve_hint, &cout);
    sink += cout.C2.x();
  }
  EXPECT_EQ(tangent::testing::AllocationCount() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace tangent::nurbs
