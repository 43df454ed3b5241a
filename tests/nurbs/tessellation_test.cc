// The tessellation's reported bound is certified: dense samples of the surface all lie within
// it of the mesh (of their own grid cell's two triangles, which is stronger).

#include "nurbs/tessellation.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "nurbs/primitives.h"
#include "tests/nurbs/random_nurbs.h"

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
}

}  // namespace
}  // namespace tangent::nurbs
