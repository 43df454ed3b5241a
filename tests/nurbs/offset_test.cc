// Offset meshes: vertices r along the exact normals, CGAL's certificate (no self-intersection
// for a paperclip offset by 0.12 mm, a Hausdorff bound of the order of the tessellation's, a
// folding warning for an offset beyond the bends' inner radius), poles, and bad input.

#include "nurbs/offset.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "nurbs/primitives.h"

namespace tangent::nurbs {
namespace {

TEST(OffsetTest, PaperclipOffsetIsCertified) {
  const NurbsSurface clip = MakeTube(PaperclipPath(), kPaperclipWireRadius);
  const OffsetMesh m = MakeOffsetMesh(clip, 20e-6, 0.1e-3);
  EXPECT_LE(m.tessellation_bound, 20e-6);
  EXPECT_NEAR(m.offset, m.tessellation_bound + 0.1e-3, 1e-18);
  for (size_t k = 0; k < m.vertices.size(); k += 7) {
    const SurfacePoint p = clip.Evaluate(m.base.uv[k][0], m.base.uv[k][1], 1);
    const Eigen::Vector3d d = m.vertices[k] - p.S;
    EXPECT_NEAR(d.norm(), m.offset, 1e-15);
    EXPECT_NEAR(d.normalized().dot(p.S_u.cross(p.S_v).normalized()), 1.0, 1e-12);
  }
  const OffsetCertificate c = CertifyOffsetMesh(clip, m, 120);
  std::printf("%s\n", c.Report("paperclip").c_str());
  EXPECT_EQ(c.self_intersecting_pairs, 0);
  EXPECT_FALSE(c.offset_exceeds_curvature);
  EXPECT_NEAR(c.min_curvature_radius, kPaperclipWireRadius, 1e-6);  // around the wire
  // The offset tube's radius is 0.45 + 0.12 mm: chords deviate by the tessellation's bound
  // scaled by (R + r)/R, plus the curvature of the bends.
  EXPECT_LT(c.hausdorff, 2.0 * m.tessellation_bound);
  EXPECT_GT(c.samples, 10000);
}

TEST(OffsetTest, AnOffsetBeyondAConcaveRadiusIsFlagged) {
  // 3 mm around a wire whose innermost bend is 2.05 mm from its centre: the offset folds.
  const NurbsSurface clip = MakeTube(PaperclipPath(), kPaperclipWireRadius);
  const OffsetMesh m = MakeOffsetMesh(clip, 50e-6, 3e-3);
  const OffsetCertificate c = CertifyOffsetMesh(clip, m, 60);
  std::printf("%s\n", c.Report("paperclip, 3 mm").c_str());
  EXPECT_TRUE(c.offset_exceeds_curvature);
  EXPECT_GT(c.self_intersecting_pairs, 0);
}

TEST(OffsetTest, SpherePolesGetTheLimitNormal) {
  const NurbsSurface sphere = MakeSphere({0, 0, 0}, 0.02);
  const OffsetMesh m = MakeOffsetMesh(sphere, 20e-6, 0.5e-3);
  for (const Eigen::Vector3d& v : m.vertices) {
    ASSERT_TRUE(v.allFinite());
    EXPECT_NEAR(v.norm(), 0.02 + m.offset, 1e-9);
  }
  const OffsetCertificate c = CertifyOffsetMesh(sphere, m, 60);
  EXPECT_EQ(c.self_intersecting_pairs, 0);
  EXPECT_NEAR(c.min_curvature_radius, 0.02, 1e-9);
}

TEST(OffsetTest, BadInputIsRejectedWithAMessage) {
  const NurbsSurface sphere = MakeSphere({0, 0, 0}, 0.02);
  try {
    MakeOffsetMesh(sphere, 0.0, 1e-3);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "offset mesh: tolerance must be positive");
  }
  try {
    MakeOffsetMesh(sphere, 1e-5, -1.0);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "offset mesh: margin must be positive");
  }
}

}  // namespace
}  // namespace tangent::nurbs
