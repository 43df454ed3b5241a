// The tessellation's reported bound is certified: dense samples of the surface all lie within
// it of the mesh (of their own grid cell's two triangles, which is stronger).

#include "nurbs/tessellation.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <string>

#include "nurbs/primitives.h"
#include "testing/random_nurbs.h"

namespace tangent::nurbs {
namespace {

// Largest distance from dense random samples to their cell's triangles.
double SampledError(const NurbsSurface& s, const TriangleMesh& m, std::mt19937_64& rng, int n) {
  double worst = 0.0;
  for (int k = 0; k < n; ++k) {
    const double u = testing::RandomParam(rng, s.knots_u());
    const double v = testing::RandomParam(rng, s.knots_v());
    worst = std::max(worst, DistanceToCell(m, u, v, EvaluateReference(s, u, v, 0).S));
  }
  return worst;
}

struct Case {
  const char* name;
  NurbsSurface surface;
  double tolerance;
};

TEST(TessellationTest, BoundHoldsAgainstDenseSampling) {
  std::mt19937_64 rng(77);
  std::vector<Case> cases = {
      {"sphere", MakeSphere(Eigen::Vector3d::Zero(), 0.05), 1e-4},
      {"torus", MakeTorus(0.05, 0.01), 2e-5},
      {"paperclip", MakeTube(PaperclipPath(), kPaperclipWireRadius), 5e-6},
      {"sheared", MakeShearedPatch(0.25, 0.05, 0.005, true), 1e-5},
      {"random_rational", testing::RandomSurface(rng, 3, 3, 7, 7, true), 1e-3},
      {"twisted_plane", MakePlanePatch({0, 0, 0}, {1, 0, 0}, {0, 1, 0}), 1.0},
  };
  for (const Case& c : cases) {
    const TriangleMesh m = Tessellate(c.surface, c.tolerance);
    const double sampled = SampledError(c.surface, m, rng, 20000);
    EXPECT_LE(m.error_bound, c.tolerance) << c.name;
    EXPECT_LE(sampled, m.error_bound * (1 + 1e-9) + 1e-15) << c.name;
    // Not wildly pessimistic either: the worst sample reaches a visible part of the bound.
    if (m.error_bound > 0) {
      EXPECT_GT(sampled, 0.02 * m.error_bound) << c.name;
    }
    EXPECT_EQ(m.triangles.size(), 2 * (m.u_lines.size() - 1) * (m.v_lines.size() - 1));
    EXPECT_EQ(m.vertices.size(), m.uv.size());
  }
}

TEST(TessellationTest, ReportsBoundWhenCappedAndRejectsBadTolerance) {
  const NurbsSurface s = MakeSphere(Eigen::Vector3d::Zero(), 1.0);
  const TriangleMesh m = Tessellate(s, 1e-9, /*max_lines=*/9);
  EXPECT_GT(m.error_bound, 1e-9);  // Could not reach the tolerance; says so.
  std::mt19937_64 rng(78);
  EXPECT_LE(SampledError(s, m, rng, 5000), m.error_bound);
  EXPECT_THROW(Tessellate(s, 0.0), std::invalid_argument);
  try {
    Tessellate(s, 1e-3, 4097, -1.0);
    FAIL() << "negative max_edge accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_edge"), std::string::npos) << e.what();
  }
}

// A paperclip's straight legs are flat: by tolerance alone a leg is one cell 20+ mm long. With
// max_edge every cell's chords are bounded, and the bound still holds.
TEST(TessellationTest, MaxEdgeBoundsTheCellsOfFlatStretches) {
  const NurbsSurface clip = MakeTube(PaperclipPath(), kPaperclipWireRadius);
  const TriangleMesh coarse = Tessellate(clip, 100e-6);
  const TriangleMesh fine = Tessellate(clip, 100e-6, 4097, 0.5e-3);
  auto longest = [&](const TriangleMesh& m) {
    double worst = 0.0;
    for (const auto& t : m.triangles) {
      for (int k = 0; k < 3; ++k) {
        worst =
            std::max(worst, (m.vertices[static_cast<size_t>(t[static_cast<size_t>(k)])] -
                             m.vertices[static_cast<size_t>(t[static_cast<size_t>((k + 1) % 3)])])
                                .norm());
      }
    }
    return worst;
  };
  EXPECT_GT(longest(coarse), 10e-3);
  // Triangle edges: the cell's two chords and its diagonal (at most sqrt(2) x max_edge).
  EXPECT_LE(longest(fine), std::sqrt(2.0) * 0.5e-3 + 1e-12);
  EXPECT_LE(fine.error_bound, 100e-6);
  std::mt19937_64 rng(79);
  EXPECT_LE(SampledError(clip, fine, rng, 5000), fine.error_bound);
}

}  // namespace
}  // namespace tangent::nurbs
