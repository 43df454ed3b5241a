// Surface evaluation benchmark: D0/D1/D2 of our three paths and of Open CASCADE's two
// evaluators, on the same bicubic surfaces and the same parameter sequences, in one run.
//
// Names: <order>/<implementation>/<rational|nonrational>/<random|span|walk>, e.g.
// "D2/ours_fast/rational/random"; implementations ours_fast, ours_reference, ours_refinement,
// occt_geom (Geom_BSplineSurface::D2, no cache), occt_adaptor (GeomAdaptor_Surface::D2, which
// caches the current span's polynomial). Patterns: random (uniform over the domain), span (random
// inside one knot span), walk (steps of ~1e-3 of the domain, as a tracked contact moves).
// After the run a table of medians and the ratios the NURBS issue targets is printed.

#include <benchmark/benchmark.h>

#include <GeomAdaptor_Surface.hxx>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "bench/median_reporter.h"
#include "nurbs/refinement.h"
#include "testing/occt_convert.h"
#include "testing/random_nurbs.h"

namespace tangent::nurbs {
namespace {

constexpr int kNumParams = 4096;  // Power of two: index wraps with a mask.

struct Params {
  std::vector<double> u, v;
};

Params MakeParams(const NurbsSurface& s, const std::string& pattern, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Params p;
  const KnotVector& ku = s.knots_u();
  const KnotVector& kv = s.knots_v();
  const double u0 = ku.domain_begin(), u1 = ku.domain_end();
  const double v0 = kv.domain_begin(), v1 = kv.domain_end();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  if (pattern == "random") {
    for (int i = 0; i < kNumParams; ++i) {
      p.u.push_back(u0 + (u1 - u0) * unit(rng));
      p.v.push_back(v0 + (v1 - v0) * unit(rng));
    }
  } else if (pattern == "span") {
    const auto bu = ku.Breakpoints(), bv = kv.Breakpoints();
    const size_t iu = bu.size() / 2 - 1, iv = bv.size() / 2 - 1;
    for (int i = 0; i < kNumParams; ++i) {
      p.u.push_back(bu[iu] + (bu[iu + 1] - bu[iu]) * unit(rng));
      p.v.push_back(bv[iv] + (bv[iv + 1] - bv[iv]) * unit(rng));
    }
  } else {  // walk: a reflected random walk with steps of 1e-3 of the domain.
    std::normal_distribution<double> step(0.0, 1e-3);
    double u = 0.5 * (u0 + u1), v = 0.5 * (v0 + v1);
    for (int i = 0; i < kNumParams; ++i) {
      u += (u1 - u0) * step(rng);
      v += (v1 - v0) * step(rng);
      if (u < u0 || u > u1) u = std::clamp(2 * std::clamp(u, u0, u1) - u, u0, u1);
      if (v < v0 || v > v1) v = std::clamp(2 * std::clamp(v, v0, v1) - v, v0, v1);
      p.u.push_back(u);
      p.v.push_back(v);
    }
  }
  return p;
}

struct Case {
  std::string name;  // rational | nonrational
  NurbsSurface surface;
  Handle(Geom_BSplineSurface) occt;
};

std::vector<Case>& Cases() {
  static std::vector<Case> cases = [] {
    std::vector<Case> out;
    std::mt19937_64 rng(12345);
    for (bool rational : {true, false}) {
      // Bicubic, 10 x 10 control points (7 x 7 non-uniform spans), as a CAD part face.
      NurbsSurface s = testing::RandomSurface(rng, 3, 3, 10, 10, rational, true);
      Handle(Geom_BSplineSurface) o = testing::ToOcct(s);
      out.push_back(Case{rational ? "rational" : "nonrational", std::move(s), o});
    }
    return out;
  }();
  return cases;
}

template <int Order>
void OursFast(benchmark::State& state, const Case& c, const Params& p) {
  SpanHint hint;
  SurfacePoint out;
  size_t i = 0;
  for (auto _ : state) {
    c.surface.Evaluate<Order>(p.u[i], p.v[i], &hint, &out);
    benchmark::DoNotOptimize(out);
    i = (i + 1) & (kNumParams - 1);
  }
}

// A slow path (reference or refinement): a free function of (surface, u, v, order).
template <int Order, SurfacePoint (*Path)(const NurbsSurface&, double, double, int)>
void OursPath(benchmark::State& state, const Case& c, const Params& p) {
  size_t i = 0;
  for (auto _ : state) {
    SurfacePoint out = Path(c.surface, p.u[i], p.v[i], Order);
    benchmark::DoNotOptimize(out);
    i = (i + 1) & (kNumParams - 1);
  }
}

template <int Order, class Surface>
void Occt(benchmark::State& state, const Surface& s, const Params& p) {
  gp_Pnt x;
  gp_Vec du, dv, duu, dvv, duv;
  size_t i = 0;
  for (auto _ : state) {
    if constexpr (Order == 0) s.D0(p.u[i], p.v[i], x);
    if constexpr (Order == 1) s.D1(p.u[i], p.v[i], x, du, dv);
    if constexpr (Order == 2) s.D2(p.u[i], p.v[i], x, du, dv, duu, dvv, duv);
    benchmark::DoNotOptimize(x);
    benchmark::DoNotOptimize(du);
    benchmark::DoNotOptimize(duu);
    i = (i + 1) & (kNumParams - 1);
  }
}

template <int Order>
void RegisterOrder(const Case& c, const std::string& pattern, const Params* p) {
  const std::string suffix = "/" + c.name + "/" + pattern;
  const std::string d = "D" + std::to_string(Order);
  benchmark::RegisterBenchmark((d + "/ours_fast" + suffix).c_str(),
                               [&c, p](benchmark::State& s) { OursFast<Order>(s, c, *p); });
  benchmark::RegisterBenchmark(
      (d + "/ours_reference" + suffix).c_str(),
      [&c, p](benchmark::State& s) { OursPath<Order, &EvaluateReference>(s, c, *p); });
  benchmark::RegisterBenchmark(
      (d + "/ours_refinement" + suffix).c_str(),
      [&c, p](benchmark::State& s) { OursPath<Order, &EvaluateByRefinement>(s, c, *p); });
  benchmark::RegisterBenchmark((d + "/occt_geom" + suffix).c_str(),
                               [&c, p](benchmark::State& s) { Occt<Order>(s, *c.occt, *p); });
  benchmark::RegisterBenchmark((d + "/occt_adaptor" + suffix).c_str(),
                               [&c, p](benchmark::State& s) {
                                 GeomAdaptor_Surface adaptor(c.occt);  // One cache per run.
                                 Occt<Order>(s, adaptor, *p);
                               });
}

void PrintSummary(const bench::MedianReporter& r) {
  std::printf("\nSurface evaluation, ns per point (median), and ratios (same run):\n");
  std::printf("%-6s %-12s %-7s %10s %10s %10s %10s %10s\n", "order", "case", "pattern", "ours_fast",
              "reference", "refinement", "occt_geom", "occt_adapt");
  for (const char* order : {"D0", "D1", "D2"}) {
    for (const Case& c : Cases()) {
      for (const char* pattern : {"random", "span", "walk"}) {
        auto t = [&](const char* impl) {
          return r.Get(std::string(order) + "/" + impl + "/" + c.name + "/" + pattern);
        };
        std::printf("%-6s %-12s %-7s %10.1f %10.1f %10.1f %10.1f %10.1f\n", order, c.name.c_str(),
                    pattern, t("ours_fast"), t("ours_reference"), t("ours_refinement"),
                    t("occt_geom"), t("occt_adaptor"));
      }
    }
  }
  std::printf(
      "\nTargets (D2, bicubic): fast at random (u,v) <= 1/8 of occt_geom at random, and\n"
      "<= 1/3 of occt_adaptor evaluated inside one span.\n");
  for (const Case& c : Cases()) {
    const double fast_random = r.Get("D2/ours_fast/" + c.name + "/random");
    const double fast_span = r.Get("D2/ours_fast/" + c.name + "/span");
    const double geom_random = r.Get("D2/occt_geom/" + c.name + "/random");
    const double adaptor_span = r.Get("D2/occt_adaptor/" + c.name + "/span");
    if (fast_random <= 0 || geom_random <= 0 || adaptor_span <= 0) continue;
    const double r1 = fast_random / geom_random;
    const double r2 = fast_random / adaptor_span;
    std::printf("  %-12s fast/occt_geom (random)         = 1/%5.1f  %s\n", c.name.c_str(), 1 / r1,
                r1 <= 1.0 / 8 ? "met (<= 1/8)" : "NOT MET (target <= 1/8)");
    std::printf("  %-12s fast(random)/occt_adaptor(span) = 1/%5.1f  %s\n", c.name.c_str(), 1 / r2,
                r2 <= 1.0 / 3 ? "met (<= 1/3)" : "NOT MET (target <= 1/3)");
    if (fast_span > 0) {
      std::printf("  %-12s fast(span)/occt_adaptor(span)   = 1/%5.1f\n", c.name.c_str(),
                  adaptor_span / fast_span);
    }
  }
}

}  // namespace
}  // namespace tangent::nurbs

int main(int argc, char** argv) {
  using namespace tangent::nurbs;
  static std::map<std::string, Params> params;
  for (const Case& c : Cases()) {
    for (const char* pattern : {"random", "span", "walk"}) {
      params[c.name + pattern] = MakeParams(c.surface, pattern, 99);
    }
  }
  for (const char* pattern : {"random", "span", "walk"}) {
    for (const Case& c : Cases()) {
      const Params* p = &params[c.name + pattern];
      RegisterOrder<0>(c, pattern, p);
      RegisterOrder<1>(c, pattern, p);
      RegisterOrder<2>(c, pattern, p);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  tangent::bench::MedianReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  PrintSummary(reporter);
  benchmark::Shutdown();
  return 0;
}
