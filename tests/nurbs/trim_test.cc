// Trimming loops: point classification against exact references on 10^5 random points (a
// rational circle's hole, decided analytically; a cubic outer loop, decided by a dense
// polygon), the signed distance and closest point against the analytic circle, and every kind
// of bad loop rejected with a message naming it.

#include "nurbs/trim.h"

#include "nurbs/primitives.h"
#include "nurbs/tessellation.h"
#include "testing/alloc_counter.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace tangent::nurbs {
namespace {

using ::testing::HasSubstr;
using V = Eigen::Vector2d;

NurbsCurve2d Circle(const V& centre, double r, bool clockwise = false) {
  return MakeCircle2d(centre, r, clockwise);
}
NurbsCurve2d Polyline(const std::vector<V>& points) { return MakePolyline2d(points); }

TrimLoop Loop(std::vector<NurbsCurve2d> curves) { return TrimLoop{std::move(curves)}; }

const V kLo(0, 0), kHi(1, 1);

TEST(TrimTest, ACircularHoleIsClassifiedExactlyOn100kPoints) {
  const V c(0.43, 0.52);
  const double r = 0.21;
  std::vector<std::string> warnings;
  const TrimmedDomain d(kLo, kHi, std::nullopt, {Loop({Circle(c, r, true)})}, {}, &warnings);
  EXPECT_TRUE(warnings.empty());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int disagreements = 0, near = 0, checked = 0, with_nearest = 0;
  const double kBand = 1e-12;  // the stated band: within it either answer is accepted
  for (int i = 0; i < 100000; ++i) {
    V p;
    if (i % 2 == 0) {
      p = V(unit(rng), unit(rng));
    } else {  // near the circle: 10^-13 .. 10^-2 off it, either side
      const double angle = 2 * M_PI * unit(rng);
      const double off = std::pow(10.0, -13.0 + 11.0 * unit(rng)) * (unit(rng) < 0.5 ? -1 : 1);
      p = c + (r + off) * V(std::cos(angle), std::sin(angle));
      near += std::abs(off) < 1e-4;  // inside the polygon's band
    }
    const double exact = (p - c).norm() - r;
    if (std::abs(exact) <= kBand) continue;
    ++checked;
    TrimmedDomain::Closest nearest;
    const bool in = d.Contains(p, &nearest);
    disagreements += in != (exact > 0.0);
    // The closest point comes back exactly when classifying needed it: within a chord's band.
    if (nearest.loop >= 0) {
      ++with_nearest;
      EXPECT_EQ(nearest.signed_distance, d.Nearest(p).signed_distance);
    }
    EXPECT_EQ(in, d.Contains(p));
  }
  EXPECT_GT(with_nearest, 10000);
  std::printf("%d points checked (%d within the polygon's band), %d disagreements\n", checked, near,
              disagreements);
  EXPECT_GT(near, 20000);
  EXPECT_EQ(disagreements, 0);
}

// A CAD face's outer loop runs round its whole parameter domain (here with one side in two
// pieces): the loop's polygon is its box, classified by comparisons instead of its chords. The
// answers must be the chords' own, at the sides and at the hole alike, and the same everywhere
// within the clearance handed back.
TEST(TrimTest, AnOuterLoopRoundTheWholeDomainIsClassifiedExactly) {
  const V c(0.43, 0.52);
  const double r = 0.21;
  const TrimmedDomain d(
      kLo, kHi,
      Loop({Polyline({V(0, 0), V(0.5, 0), V(1, 0), V(1, 1), V(0, 1), V(0, 0.5), V(0, 0)})}),
      {Loop({Circle(c, r, true)})});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int disagreements = 0, checked = 0, near_sides = 0, with_clearance = 0, moved_disagreements = 0,
      excluded = 0;
  for (int i = 0; i < 100000; ++i) {
    V p(unit(rng), unit(rng));
    if (i % 2 == 1) {  // 10^-13 .. 10^-2 from a side, either way
      const double off = std::pow(10.0, -13.0 + 11.0 * unit(rng)) * (unit(rng) < 0.5 ? -1 : 1);
      const int side = static_cast<int>(4 * unit(rng));
      p[side % 2] = side < 2 ? off : 1.0 - off;
      near_sides += std::abs(off) < 1e-4;
    }
    const double to_sides = std::min({p.x(), 1.0 - p.x(), p.y(), 1.0 - p.y()});
    const double exact = std::min(to_sides, (p - c).norm() - r);
    if (std::abs(exact) <= 1e-12) continue;
    ++checked;
    TrimmedDomain::Closest nearest;
    const bool in = d.Contains(p, &nearest);
    disagreements += in != (exact > 0.0);
    EXPECT_EQ(in, d.Contains(p));
    if (nearest.loop >= 0) {
      EXPECT_EQ(nearest.signed_distance, d.Nearest(p).signed_distance);
    }
    // Within the clearance it hands back, every point has the same answer (the servo's trimmed
    // contacts skip the classification there).
    double clearance = -1.0;
    int excluded_by = -2;
    EXPECT_EQ(d.Contains(p, nullptr, &clearance, &excluded_by), in);
    EXPECT_GE(clearance, 0.0);
    // Off the material beyond every band, the loop that excludes the point is its nearest (off
    // the domain, none does).
    const bool in_domain = (p.array() >= kLo.array()).all() && (p.array() <= kHi.array()).all();
    if (!in && nearest.loop < 0 && in_domain) {
      ++excluded;
      EXPECT_EQ(excluded_by, d.Nearest(p).loop);
    } else {
      EXPECT_EQ(excluded_by, -1);
    }
    if (clearance > 0.0) {
      ++with_clearance;
      EXPECT_LE(clearance, std::abs(exact) + 1e-12);  // never past the loops or the border
      const double angle = 2 * M_PI * unit(rng);
      const V q = p + 0.999 * clearance * V(std::cos(angle), std::sin(angle));
      moved_disagreements += d.Contains(q) != in;
    }
  }
  EXPECT_GT(with_clearance, 40000);
  EXPECT_GT(excluded, 5000);
  EXPECT_EQ(moved_disagreements, 0);
  EXPECT_GT(near_sides, 20000);
  EXPECT_EQ(disagreements, 0) << checked << " points checked";
}

TEST(TrimTest, SignedDistanceAndClosestPointMatchTheCircle) {
  const V c(0.5, 0.5);
  const double r = 0.2;
  const TrimmedDomain d(kLo, kHi, std::nullopt, {Loop({Circle(c, r, true)})});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double angle = 2 * M_PI * unit(rng);
    const V p = c + (r * (0.3 + 1.4 * unit(rng))) * V(std::cos(angle), std::sin(angle));
    const TrimmedDomain::Closest n = d.Nearest(p);
    const double exact = (p - c).norm() - r;  // > 0 outside the hole: material
    worst = std::max(worst, std::abs(n.signed_distance - exact));
    EXPECT_NEAR((n.point - c).norm(), r, 1e-14);
    const V on = d.loops()[0].curves[0].Evaluate(n.t, 0).C;
    EXPECT_NEAR((on - n.point).norm(), 0.0, 1e-15);
  }
  std::printf("largest signed-distance error %.2e\n", worst);
  EXPECT_LT(worst, 1e-13);
}

TEST(TrimTest, ACubicOuterLoopAgreesWithADensePolygonOutsideItsBand) {
  // Two cubic Béziers forming a blob, counter-clockwise, with a square polyline hole.
  const NurbsCurve2d upper(KnotVector(3, {0, 0, 0, 0, 1, 1, 1, 1}),
                           {V(0.1, 0.5), V(0.1, 1.1), V(0.9, 0.7), V(0.9, 0.4)}, {1, 2, 0.5, 1});
  const NurbsCurve2d lower(KnotVector(3, {0, 0, 0, 0, 1, 1, 1, 1}),
                           {V(0.9, 0.4), V(0.9, -0.1), V(0.2, 0.0), V(0.1, 0.5)});
  std::vector<std::string> warnings;
  // Given clockwise on purpose: reversed with a warning.
  const TrimmedDomain cw(kLo, kHi, Loop({upper, lower}), {}, {}, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("outer loop ran clockwise; reversed"));
  const TrimmedDomain d(
      kLo, kHi, cw.loops()[0],
      {Loop({Polyline({V(0.4, 0.3), V(0.4, 0.5), V(0.6, 0.5), V(0.6, 0.3), V(0.4, 0.3)})})});
  // The reference: each curve sampled densely, crossings counted exactly on that polygon.
  std::vector<V> dense;
  for (const NurbsCurve2d* f : {&d.loops()[0].curves[0], &d.loops()[0].curves[1]}) {
    for (int k = 0; k < 5000; ++k) dense.push_back(f->Evaluate(k / 5000.0, 0).C);
  }
  auto in_dense = [&](const V& p) {
    bool in = false;
    for (size_t i = 0, j = dense.size() - 1; i < dense.size(); j = i++) {
      if ((dense[i][1] > p[1]) != (dense[j][1] > p[1]) &&
          p[0] < (dense[j][0] - dense[i][0]) * (p[1] - dense[i][1]) / (dense[j][1] - dense[i][1]) +
                     dense[i][0]) {
        in = !in;
      }
    }
    return in;
  };
  auto dense_distance = [&](const V& p) {
    double best = 1e300;
    for (size_t i = 0, j = dense.size() - 1; i < dense.size(); j = i++) {
      const V e = dense[i] - dense[j];
      const double f = std::clamp((p - dense[j]).dot(e) / e.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (dense[j] + f * e - p).norm());
    }
    return best;
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int disagreements = 0, checked = 0;
  for (int i = 0; i < 100000; ++i) {
    const V p(unit(rng), unit(rng));
    const bool in_hole = p[0] > 0.4 && p[0] < 0.6 && p[1] > 0.3 && p[1] < 0.5;
    const bool reference = in_dense(p) && !in_hole;
    const bool ours = d.Contains(p);
    if (ours == reference) {
      ++checked;
      continue;
    }
    // Disagreement: only acceptable within the dense polygon's own error (its chords' sagitta,
    // below 1e-6 here) of the outer curve, or on the hole's edge.
    const double to_hole = std::min(
        {std::abs(p[0] - 0.4), std::abs(p[0] - 0.6), std::abs(p[1] - 0.3), std::abs(p[1] - 0.5)});
    if (dense_distance(p) > 1e-6 && to_hole > 1e-15) ++disagreements;
  }
  std::printf("%d agree, %d disagreements outside the reference's band\n", checked, disagreements);
  EXPECT_EQ(disagreements, 0);
  // The polyline hole's corners: a point diagonally off a corner is off the material.
  EXPECT_FALSE(d.Contains(V(0.4 + 1e-9, 0.3 + 1e-9)));
  EXPECT_TRUE(d.Contains(V(0.4 - 1e-9, 0.3 - 1e-9)));
  EXPECT_NEAR(d.Nearest(V(0.4 - 3e-9, 0.3 - 4e-9)).signed_distance, 5e-9, 1e-15);
}

std::string ErrorOf(std::optional<TrimLoop> outer, std::vector<TrimLoop> holes) {
  try {
    TrimmedDomain(kLo, kHi, std::move(outer), std::move(holes));
  } catch (const TrimError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted";
  return "";
}

TEST(TrimTest, BadLoopsAreRejectedNamingTheLoopAndCurve) {
  const TrimLoop square =
      Loop({Polyline({V(0.1, 0.1), V(0.9, 0.1), V(0.9, 0.9), V(0.1, 0.9), V(0.1, 0.1)})});
  // Open: two curves that do not meet.
  EXPECT_THAT(ErrorOf(std::nullopt, {Loop({Polyline({V(0.2, 0.2), V(0.3, 0.2), V(0.3, 0.3)}),
                                           Polyline({V(0.3, 0.31), V(0.2, 0.2)})})}),
              HasSubstr("hole 0 is not closed: curve 0 ends at (0.3, 0.3) but curve 1 starts at "
                        "(0.3, 0.31): a gap of 0.01"));
  // Crossing loops: two holes overlapping.
  EXPECT_THAT(
      ErrorOf(square, {Loop({Circle(V(0.4, 0.5), 0.15)}), Loop({Circle(V(0.6, 0.5), 0.15)})}),
      HasSubstr("hole 1 crosses or touches the hole 0"));
  // A figure of eight.
  EXPECT_THAT(ErrorOf(std::nullopt, {Loop({Polyline({V(0.2, 0.2), V(0.4, 0.4), V(0.4, 0.2),
                                                     V(0.2, 0.4), V(0.2, 0.2)})})}),
              HasSubstr("hole 0 crosses or touches itself"));
  // Outside the domain.
  EXPECT_THAT(ErrorOf(std::nullopt, {Loop({Circle(V(0.95, 0.5), 0.1)})}),
              HasSubstr("hole 0: curve 0 leaves the surface's domain (0, 0) to (1, 1) at"));
  // A hole outside the outer loop, and one inside another.
  EXPECT_THAT(ErrorOf(Loop({Circle(V(0.3, 0.3), 0.2)}), {Loop({Circle(V(0.8, 0.8), 0.1)})}),
              HasSubstr("hole 0 is not inside the outer loop"));
  EXPECT_THAT(ErrorOf(square, {Loop({Circle(V(0.5, 0.5), 0.3)}), Loop({Circle(V(0.5, 0.5), 0.1)})}),
              HasSubstr("hole 1 lies inside hole 0"));
  // A hole tangent to the outer loop.
  EXPECT_THAT(ErrorOf(square, {Loop({Circle(V(0.5, 0.3), 0.2)})}),
              HasSubstr("hole 0 crosses or touches the outer loop"));
  // A loop that goes out and comes back the same way.
  EXPECT_THAT(
      ErrorOf(std::nullopt,
              {Loop({Polyline({V(0.2, 0.2), V(0.4, 0.4)}), Polyline({V(0.4, 0.4), V(0.2, 0.2)})})}),
      HasSubstr("hole 0 turns back on itself"));
  // A loop with no curves.
  EXPECT_THAT(ErrorOf(square, {Loop({})}), HasSubstr("hole 0 has no curves"));
}

TEST(TrimTest, ANearlyTangentHoleIsSeparatedByRefiningTheBands) {
  // 1e-7 from the outer loop: the bands (1e-4 of the diagonal) overlap there at first and are
  // halved until they part; the thin sliver of material between them is classified exactly.
  const TrimLoop square =
      Loop({Polyline({V(0.1, 0.1), V(0.9, 0.1), V(0.9, 0.9), V(0.1, 0.9), V(0.1, 0.1)})});
  const TrimmedDomain d(kLo, kHi, square, {Loop({Circle(V(0.5, 0.3 + 1e-7), 0.2, true)})});
  EXPECT_TRUE(d.Contains(V(0.5, 0.1 + 0.5e-7)));   // the sliver
  EXPECT_FALSE(d.Contains(V(0.5, 0.1 + 1.5e-7)));  // in the hole
  EXPECT_FALSE(d.Contains(V(0.5, 0.1 - 0.5e-7)));  // outside the outer loop
  EXPECT_NEAR(d.Nearest(V(0.5, 0.1 + 0.25e-7)).signed_distance, 0.25e-7, 1e-15);
}

TEST(TrimTest, HolesGivenCounterClockwiseAreReversedWithAWarning) {
  std::vector<std::string> warnings;
  const TrimmedDomain d(kLo, kHi, std::nullopt, {Loop({Circle(V(0.5, 0.5), 0.2)})}, {}, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("hole 0 ran counter-clockwise; reversed"));
  EXPECT_FALSE(d.Contains(V(0.5, 0.5)));
  EXPECT_TRUE(d.Contains(V(0.05, 0.05)));
  EXPECT_FALSE(d.Contains(V(1.5, 0.5)));  // off the domain
  EXPECT_NEAR(d.Nearest(V(0.5, 0.5)).signed_distance, -0.2, 1e-14);
}

TEST(TrimTest, ClassifyingAndMeasuringAllocateNothing) {
  // TrimmedContactTerm calls Contains and Nearest inside a solve (Term::Evaluate's contract:
  // allocation free), near the boundary and far from it; the counter's positive control is in
  // no_allocation_test.
  const TrimmedDomain d(
      kLo, kHi,
      Loop({Polyline({V(0.05, 0.05), V(0.95, 0.05), V(0.95, 0.95), V(0.05, 0.95), V(0.05, 0.05)})}),
      {Loop({Circle(V(0.5, 0.5), 0.2, true)})});
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<V> points;
  for (int i = 0; i < 1000; ++i) points.emplace_back(unit(rng), unit(rng));
  points.emplace_back(0.7 + 1e-9, 0.5);  // within the band of the hole
  double sink = 0.0;
  const long before = tangent::testing::AllocationCount();
  for (const V& p : points) sink += d.Contains(p);
  const long after_contains = tangent::testing::AllocationCount();
  for (const V& p : points) sink += d.Nearest(p).signed_distance;
  EXPECT_EQ(after_contains - before, 0) << "Contains";
  EXPECT_EQ(tangent::testing::AllocationCount() - after_contains, 0) << "Nearest";
  EXPECT_TRUE(std::isfinite(sink));
}

// A mesh cut along a trim keeps every cell that holds material (so the certified bound still
// covers all of it) and drops cells wholly off it: checked on 10^5 random points against the
// exact classification, and cells dropped only where no point of them is material.
TEST(TrimTest, AMeshCutAlongATrimKeepsEveryCellWithMaterial) {
  const NurbsSurface plane = MakePlanePatch({0, 0, 0}, {0.04, 0, 0}, {0, 0.04, 0});
  const TriangleMesh full = Tessellate(plane, 1e-6, 4097, 0.5e-3);
  const TrimmedDomain d(
      kLo, kHi,
      Loop({Polyline({{0.05, 0.05}, {0.95, 0.1}, {0.9, 0.95}, {0.1, 0.9}, {0.05, 0.05}})}),
      {Loop({Circle({0.5, 0.5}, 0.2, true)})});
  const TriangleMesh cut = CutAlongTrim(full, d);
  ASSERT_EQ(cut.cells.size(), cut.triangles.size());
  const size_t nv = full.v_lines.size() - 1;
  std::vector<char> kept((full.u_lines.size() - 1) * nv, 0);
  for (int c : cut.cells) kept[static_cast<size_t>(c)] = 1;
  auto cell_of = [&](const V& p) {
    const auto i = std::upper_bound(full.u_lines.begin() + 1, full.u_lines.end() - 1, p[0]) -
                   full.u_lines.begin() - 1;
    const auto j = std::upper_bound(full.v_lines.begin() + 1, full.v_lines.end() - 1, p[1]) -
                   full.v_lines.begin() - 1;
    return static_cast<size_t>(i) * nv + static_cast<size_t>(j);
  };
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int material = 0, lost = 0;
  for (int k = 0; k < 100000; ++k) {
    const V p(unit(rng), unit(rng));
    if (!d.Contains(p)) continue;
    ++material;
    lost += !kept[cell_of(p)];
  }
  // Every dropped cell: its centre off the material and no loop within it (sampled densely).
  int dropped = 0, dropped_with_material = 0;
  for (size_t c = 0; c < kept.size(); ++c) {
    if (kept[c]) continue;
    ++dropped;
    const size_t i = c / nv, j = c % nv;
    for (int a = 0; a <= 8; ++a) {
      for (int b = 0; b <= 8; ++b) {
        const V p(full.u_lines[i] + (full.u_lines[i + 1] - full.u_lines[i]) * a / 8.0,
                  full.v_lines[j] + (full.v_lines[j + 1] - full.v_lines[j]) * b / 8.0);
        dropped_with_material += d.Contains(p);
      }
    }
  }
  std::printf(
      "cut along a trim: %zu of %zu triangles kept, %d cells dropped; %d material points, "
      "%d in dropped cells\n",
      cut.triangles.size(), full.triangles.size(), dropped, material, lost);
  EXPECT_EQ(lost, 0);
  EXPECT_EQ(dropped_with_material, 0);
  EXPECT_GT(dropped, static_cast<int>(kept.size() / 5));  // the hole and the corners go
  // A second cut changes nothing (cells carried through).
  EXPECT_EQ(CutAlongTrim(cut, d).triangles.size(), cut.triangles.size());
}

}  // namespace
}  // namespace tangent::nurbs
