// The servo-loop evaluators never touch the heap: every global operator new is counted while
// they run. (Counting operator new catches std::vector, Eigen dynamic types and anything else
// routed through the C++ allocator.)

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "nurbs/curve.h"
#include "nurbs/primitives.h"
#include "nurbs/surface.h"
#include "tests/nurbs/random_nurbs.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace tangent::nurbs {
namespace {

TEST(NoAllocationTest, CounterSeesAllocations) {
  const long before = g_allocations.load();
  auto* v = new std::vector<double>(100);
  delete v;
  EXPECT_GE(g_allocations.load() - before, 2);  // The counter is live: this test can fail.
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
  const long before = g_allocations.load();
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
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace tangent::nurbs
