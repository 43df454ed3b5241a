// Evaluation where CAD parts need it and well-spaced test surfaces never go (issue 13): knot
// spans far shorter than their neighbours — one nearly repeated knot, or geometrically graded
// spans — down to a ratio of 1e-9, at degrees 1–9, rational and not. Every path (the fast span
// form, the reference basis functions, Oslo refinement) is held to 1e-12 relative per
// derivative family against an exact rational truth (tests/nurbs/exact_truth.h; long double is
// not enough there: A'' from the blossom divides by h²).

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>

#include "nurbs/curve.h"
#include "nurbs/refinement.h"
#include "nurbs/surface.h"
#include "testing/random_nurbs.h"
#include "tests/nurbs/exact_truth.h"

namespace tangent::nurbs {
namespace {

constexpr double kRelTol = 1e-12;  // issue 13: "1e-12 relative, all orders"

// Relative error of one derivative family, scaled by its largest member at that point (as in
// evaluation_test.cc); a family that is exactly zero (a bilinear patch's S_uu) is judged
// against the first derivatives' scale over the span instead.
double FamilyError(const SurfacePoint& a, const SurfacePoint& b, int order, double fallback) {
  auto err = [&](std::initializer_list<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs) {
    double scale = 0.0, diff = 0.0;
    for (const auto& [x, y] : pairs) {
      scale = std::max(scale, y.norm());
      diff = std::max(diff, (x - y).norm());
    }
    return diff / (scale > 0.0 ? scale : fallback);
  };
  if (order == 0) return err({{a.S, b.S}});
  if (order == 1) return err({{a.S_u, b.S_u}, {a.S_v, b.S_v}});
  return err({{a.S_uu, b.S_uu}, {a.S_uv, b.S_uv}, {a.S_vv, b.S_vv}});
}

enum class Spacing { kOneShortSpan, kGraded };

// Clamped knots of degree p with n basis functions on [0.25, ...): regular spans of length 1
// (jittered by the seed), with either one span `ratio` times as long in the middle, or spans
// shrinking geometrically from 1 to `ratio`.
KnotVector Knots(int p, int n, Spacing spacing, double ratio, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> jitter(0.8, 1.2);
  const int interior = n - p - 1;
  const int spans = interior + 1;
  std::vector<double> k(static_cast<size_t>(p + 1), 0.25);
  double t = 0.25;
  for (int i = 0; i < spans; ++i) {
    double h = jitter(rng);
    if (spacing == Spacing::kOneShortSpan && i == spans / 2) h = ratio;
    if (spacing == Spacing::kGraded && spans > 1) {
      h = std::pow(ratio, static_cast<double>(i) / (spans - 1));
    }
    t += h;
    if (i + 1 < spans) k.push_back(t);
  }
  for (int i = 0; i <= p; ++i) k.push_back(t);
  return KnotVector(p, std::move(k));
}

NurbsSurface Surface(int p, int q, bool rational, Spacing spacing, double ratio,
                     std::mt19937_64& rng) {
  KnotVector ku = Knots(p, p + 5, spacing, ratio, rng);
  KnotVector kv = Knots(q, q + 4, spacing, ratio, rng);
  return testing::RandomSheet(rng, std::move(ku), std::move(kv), rational);
}

// One sample inside every span (so the short ones are always hit), alternately near its start
// and near its end (the exact truth costs ~1 ms a point at degree 9: 25 points per surface).
std::vector<double> Samples(const KnotVector& k) {
  std::vector<double> out;
  const std::vector<double> b = k.Breakpoints();
  for (size_t i = 0; i + 1 < b.size(); ++i) {
    out.push_back(b[i] + (i % 2 ? 0.9 : 0.1) * (b[i + 1] - b[i]));
  }
  return out;
}

struct Worst {
  double error[3][3] = {};  // [path][order]
};

TEST(ShortSpanTest, EveryPathIsExactToAPartInATrillionForSpansDownTo1e9) {
  const int degrees[][2] = {{1, 1}, {2, 2}, {3, 3}, {2, 3}, {1, 3}, {4, 4}, {5, 3}, {7, 6}, {9, 9}};
  const double ratios[] = {1e-1, 1e-3, 1e-5, 1e-7, 1e-9};
  const char* paths[3] = {"fast", "reference", "refinement"};
  std::mt19937_64 rng(1313);
  std::printf("worst relative error per derivative order (S, first, second) and path\n");
  for (Spacing spacing : {Spacing::kOneShortSpan, Spacing::kGraded}) {
    for (double ratio : ratios) {
      Worst worst;
      for (const auto& d : degrees) {
        for (bool rational : {false, true}) {
          const NurbsSurface s = Surface(d[0], d[1], rational, spacing, ratio, rng);
          const std::vector<double> us = Samples(s.knots_u()), vs = Samples(s.knots_v());
          for (size_t a = 0; a < us.size(); ++a) {
            for (size_t b = 0; b < vs.size(); ++b) {
              const SurfacePoint truth = testing::EvaluateExact(s, us[a], vs[b]);
              const SurfacePoint got[3] = {s.Evaluate(us[a], vs[b]),
                                           EvaluateReference(s, us[a], vs[b]),
                                           EvaluateByRefinement(s, us[a], vs[b])};
              const double fallback = std::max(truth.S_u.norm(), truth.S_v.norm());
              for (int path = 0; path < 3; ++path) {
                for (int order = 0; order <= 2; ++order) {
                  const double e = FamilyError(got[path], truth, order, fallback);
                  worst.error[path][order] = std::max(worst.error[path][order], e);
                  EXPECT_LE(e, kRelTol)
                      << paths[path] << " path, order " << order << ", degrees " << d[0] << "x"
                      << d[1] << (rational ? " rational" : "") << ", span ratio " << ratio
                      << (spacing == Spacing::kGraded ? " (graded)" : " (one short span)")
                      << " at (" << us[a] << ", " << vs[b] << ")";
                }
              }
            }
          }
        }
      }
      for (int path = 0; path < 3; ++path) {
        std::printf("%-16s ratio %.0e  %-10s  %.1e  %.1e  %.1e\n",
                    spacing == Spacing::kGraded ? "graded" : "one short span", ratio, paths[path],
                    worst.error[path][0], worst.error[path][1], worst.error[path][2]);
      }
    }
  }
}

TEST(ShortSpanTest, CurvesToo) {
  std::mt19937_64 rng(1314);
  std::uniform_real_distribution<double> coord(-1.0, 1.0), weight(0.5, 2.0);
  double worst[3] = {};
  for (Spacing spacing : {Spacing::kOneShortSpan, Spacing::kGraded}) {
    for (double ratio : {1e-1, 1e-3, 1e-5, 1e-7, 1e-9}) {
      for (int p = 1; p <= 9; ++p) {
        for (bool rational : {false, true}) {
          const int n = p + 6;
          KnotVector k = Knots(p, n, spacing, ratio, rng);
          std::vector<Eigen::Vector3d> pts;
          std::vector<double> w;
          for (int i = 0; i < n; ++i) {
            pts.emplace_back(i + 0.3 * coord(rng), coord(rng), coord(rng));
            if (rational) w.push_back(weight(rng));
          }
          const NurbsCurve<3> c(std::move(k), pts, w);
          for (double t : Samples(c.knots())) {
            const CurvePoint<3> truth = testing::EvaluateExact(c, t);
            const CurvePoint<3> paths[3] = {c.Evaluate(t), EvaluateReference(c, t),
                                            EvaluateByRefinement(c, t)};
            for (int path = 0; path < 3; ++path) {
              const Eigen::Vector3d d[3] = {paths[path].C - truth.C, paths[path].C1 - truth.C1,
                                            paths[path].C2 - truth.C2};
              const double scale[3] = {truth.C.norm(), truth.C1.norm(),
                                       truth.C2.norm() > 0 ? truth.C2.norm() : truth.C1.norm()};
              for (int order = 0; order <= 2; ++order) {
                const double e = d[order].norm() / scale[order];
                worst[path] = std::max(worst[path], e);
                EXPECT_LE(e, kRelTol) << "path " << path << ", order " << order << ", degree " << p
                                      << ", ratio " << ratio << " at t = " << t;
              }
            }
          }
        }
      }
    }
  }
  std::printf(
      "curves, degrees 1-9, span ratios to 1e-9: worst relative error fast %.1e, "
      "reference %.1e, refinement %.1e\n",
      worst[0], worst[1], worst[2]);
}

// Issue 38: a non-rational bicubic at a span ratio of 1e-1 reached 1.1e-12 in S_uu on surfaces
// outside this suite, where the test above (two bicubics per ratio) saw 5e-13. Many bicubics,
// rational and not, at moderate ratios, some far from the origin as CAD parts are, sampled
// across every span. (The power form's certification measured against each family's largest
// value on the span let 1.6e-12 through here; with no certification at all, 1.8e-9 at 1e-2.)
TEST(ShortSpanTest, BicubicsAtModerateRatiosAreExactEverywhereInTheSpan) {
  std::mt19937_64 rng(3813);
  std::uniform_real_distribution<double> offset(-50.0, 50.0);
  for (double ratio : {0.5, 0.3, 1e-1, 3e-2, 1e-2}) {
    double worst[3] = {};
    double by_kind[4] = {};
    for (int k = 0; k < 16; ++k) {
      const bool rational = k % 2;
      NurbsSurface s = Surface(3, 3, rational, Spacing::kOneShortSpan, ratio, rng);
      if (k % 4 >= 2) {
        const Eigen::Vector3d shift(offset(rng), offset(rng), offset(rng));
        std::vector<Eigen::Vector3d> pts;
        std::vector<double> w;
        for (int i = 0; i < s.num_u(); ++i) {
          for (int j = 0; j < s.num_v(); ++j) {
            pts.push_back(s.point(i, j) + shift);
            if (rational) w.push_back(s.weight(i, j));
          }
        }
        s = NurbsSurface(s.knots_u(), s.knots_v(), pts, w);
      }
      const std::vector<double> bu = s.knots_u().Breakpoints(), bv = s.knots_v().Breakpoints();
      for (size_t a = 0; a + 1 < bu.size(); ++a) {
        for (size_t b = 0; b + 1 < bv.size(); ++b) {
          for (const auto& [fu, fv] :
               {std::pair{0.05, 0.05}, {0.05, 0.95}, {0.5, 0.5}, {0.95, 0.05}, {0.95, 0.95}}) {
            const double u = bu[a] + fu * (bu[a + 1] - bu[a]);
            const double v = bv[b] + fv * (bv[b + 1] - bv[b]);
            const SurfacePoint truth = testing::EvaluateExact(s, u, v);
            const SurfacePoint got = s.Evaluate(u, v);
            const double fallback = std::max(truth.S_u.norm(), truth.S_v.norm());
            for (int order = 0; order <= 2; ++order) {
              const double e = FamilyError(got, truth, order, fallback);
              worst[order] = std::max(worst[order], e);
              if (order == 2) by_kind[k % 4] = std::max(by_kind[k % 4], e);
              EXPECT_LE(e, kRelTol) << "order " << order << (rational ? " rational" : "")
                                    << ", span ratio " << ratio << " at (" << u << ", " << v << ")";
            }
          }
        }
      }
    }
    std::printf(
        "bicubics, one span %.0e of its neighbours: worst S %.1e, first %.1e, second %.1e\n", ratio,
        worst[0], worst[1], worst[2]);
    std::printf("  second: plain %.1e, rational %.1e, shifted %.1e, shifted rational %.1e\n",
                by_kind[0], by_kind[1], by_kind[2], by_kind[3]);
  }
}

// The span form keeps the power basis (the fast kernels) wherever it is exact, and only there.
TEST(ShortSpanTest, OnlyShortSpansLeaveThePowerForm) {
  std::mt19937_64 rng(1315);
  const NurbsSurface even = Surface(3, 3, true, Spacing::kOneShortSpan, 1.0, rng);
  EXPECT_EQ(even.span_form().net_form_spans(), 0);
  const NurbsSurface shorter = Surface(3, 3, true, Spacing::kOneShortSpan, 1e-5, rng);
  const int nu = shorter.span_form().num_spans_u(), nv = shorter.span_form().num_spans_v();
  // The short span's row and column, at most.
  EXPECT_GE(shorter.span_form().net_form_spans(), 1);
  EXPECT_LE(shorter.span_form().net_form_spans(), nu + nv - 1);
  std::printf("bicubic with a 1e-5 span: %d of %d spans in the Bernstein form\n",
              shorter.span_form().net_form_spans(), nu * nv);
}

// What the certification costs: the spans of random well-spaced surfaces (degrees 1–3, random
// knots, rational and not) that leave the power form for the slower Bernstein kernel.
TEST(ShortSpanTest, WellSpacedSurfacesKeepThePowerFormAlmostEverywhere) {
  std::mt19937_64 rng(1316);
  std::uniform_int_distribution<int> degree(1, 3), count(0, 6);
  int spans = 0, net = 0;
  for (int k = 0; k < 200; ++k) {
    const int p = degree(rng), q = degree(rng);
    const NurbsSurface s =
        testing::RandomSurface(rng, p, q, p + 1 + count(rng), q + 1 + count(rng), k % 2 == 1);
    spans += s.span_form().num_spans_u() * s.span_form().num_spans_v();
    net += s.span_form().net_form_spans();
  }
  std::printf("200 random degree 1-3 surfaces: %d of %d spans in the Bernstein form (%.2f %%)\n",
              net, spans, 100.0 * net / spans);
  EXPECT_LE(net, spans / 20);
}

}  // namespace
}  // namespace tangent::nurbs
