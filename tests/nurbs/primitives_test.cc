// Primitives against their analytic shapes: radius errors at the level of rounding.

#include "nurbs/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace tangent::nurbs {
namespace {

// Sample a surface on a grid including the domain edges and poles.
template <class F>
void ForGrid(const NurbsSurface& s, int n, F&& f) {
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = s.knots_u().domain_begin() +
                       (s.knots_u().domain_end() - s.knots_u().domain_begin()) * i / n;
      const double v = s.knots_v().domain_begin() +
                       (s.knots_v().domain_end() - s.knots_v().domain_begin()) * j / n;
      f(u, v, s.Evaluate(u, v));
    }
  }
}

TEST(PrimitivesTest, SphereRadiusExactIncludingPoles) {
  const Eigen::Vector3d center(0.1, -0.2, 0.3);
  const NurbsSurface s = MakeSphere(center, 1.0);
  double worst = 0.0;
  ForGrid(s, 200, [&](double, double, const SurfacePoint& p) {
    worst = std::max(worst, std::abs((p.S - center).norm() - 1.0));
  });
  EXPECT_LE(worst, 1e-14);
  // Outward normal away from the poles; S_u vanishes at the poles (degenerate parameterization).
  const SurfacePoint eq = s.Evaluate(0.1, 0.5);
  EXPECT_GT(eq.S_u.cross(eq.S_v).dot(eq.S - center), 0.0);
  EXPECT_LT(s.Evaluate(0.3, 0.0).S_u.norm(), 1e-14);
  EXPECT_LT(s.Evaluate(0.3, 1.0).S_u.norm(), 1e-14);
}

TEST(PrimitivesTest, TransformedSurfaceIsTheMovedSurface) {
  const NurbsSurface torus = MakeTorus(0.05, 0.01);
  const Eigen::Isometry3d X = Eigen::Translation3d(0.1, -0.2, 0.3) *
                              Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, 2, -1).normalized());
  const NurbsSurface moved = Transformed(torus, X);
  double worst = 0.0;
  ForGrid(torus, 40, [&](double u, double v, const SurfacePoint& p) {
    const SurfacePoint m = moved.Evaluate(u, v);
    worst = std::max({worst, (m.S - X * p.S).norm(), (m.S_u - X.linear() * p.S_u).norm(),
                      (m.S_vv - X.linear() * p.S_vv).norm()});
  });
  EXPECT_LT(worst, 1e-14);
}

// S'(u, v) = S(a + b − u, v): the same points, u-derivatives negated, the normal turned over; a
// surface with a non-uniform knot vector and weights (a torus) so the mirrored knots matter.
// (Second u-derivatives are one-sided at the arcs' joints, so only first ones are compared.)
TEST(PrimitivesTest, ReversedUIsTheSameSurfaceFacingTheOtherWay) {
  const NurbsSurface torus = Transformed(MakeTorus(0.05, 0.01), Eigen::Isometry3d::Identity());
  const NurbsSurface reversed = ReversedU(torus);
  const double ab = torus.knots_u().domain_begin() + torus.knots_u().domain_end();
  EXPECT_EQ(reversed.knots_u().domain_begin(), torus.knots_u().domain_begin());
  EXPECT_EQ(reversed.knots_u().domain_end(), torus.knots_u().domain_end());
  double worst = 0.0;
  ForGrid(torus, 40, [&](double u, double v, const SurfacePoint& p) {
    const SurfacePoint r = reversed.Evaluate(ab - u, v);
    const Eigen::Vector3d n = p.S_u.cross(p.S_v), nr = r.S_u.cross(r.S_v);
    worst = std::max({worst, (r.S - p.S).norm(), (r.S_u + p.S_u).norm(), (r.S_v - p.S_v).norm(),
                      (nr + n).norm()});
  });
  EXPECT_LT(worst, 1e-13);
  EXPECT_EQ(reversed.periodic_u(), torus.periodic_u());
}

// A barrel's profile is its crown circle: every point's distance from the crown circle's centre
// (radius − crown from the axis, at mid-height, in the point's own meridian plane) is the crown
// radius; the widest point is `radius` at mid-height; the normal points outward.
TEST(PrimitivesTest, BarrelProfileIsTheCrownCircle) {
  const double radius = 4e-3, height = 8e-3, crown = 20e-3;
  const NurbsSurface barrel = MakeBarrel(radius, height, crown);
  double worst = 0.0;
  ForGrid(barrel, 40, [&](double, double, const SurfacePoint& p) {
    const double rho = std::hypot(p.S.x(), p.S.y());
    worst = std::max(worst,
                     std::abs(std::hypot(rho - (radius - crown), p.S.z() - 0.5 * height) - crown));
    const Eigen::Vector3d n = p.S_u.cross(p.S_v);
    EXPECT_GT(n.dot(Eigen::Vector3d(p.S.x(), p.S.y(), 0.0)), 0.0);
  });
  EXPECT_LT(worst, 1e-17);
  EXPECT_NEAR(std::hypot(barrel.Evaluate(0.3, 0.5).S.x(), barrel.Evaluate(0.3, 0.5).S.y()), radius,
              1e-17);
  EXPECT_NEAR(barrel.Evaluate(0.3, 1.0).S.z(), height, 1e-18);
  EXPECT_THROW(MakeBarrel(radius, height, 3e-3), std::invalid_argument);  // crown < height / 2
}

TEST(PrimitivesTest, CylinderAndTorusRadii) {
  const NurbsSurface cyl = MakeCylinder(0.02, 0.1);
  const NurbsSurface torus = MakeTorus(0.05, 0.01);
  double worst_cyl = 0.0, worst_torus = 0.0;
  ForGrid(cyl, 100, [&](double, double v, const SurfacePoint& p) {
    worst_cyl = std::max(worst_cyl, std::abs(p.S.head<2>().norm() - 0.02));
    EXPECT_NEAR(p.S.z(), 0.1 * v, 1e-16);
  });
  ForGrid(torus, 100, [&](double, double, const SurfacePoint& p) {
    const double ring = p.S.head<2>().norm() - 0.05;
    worst_torus = std::max(worst_torus, std::abs(std::hypot(ring, p.S.z()) - 0.01));
  });
  EXPECT_LE(worst_cyl, 1e-16);  // 0.02 m radius: 1e-16 m is ~30 ulp.
  EXPECT_LE(worst_torus, 1e-16);
}

// A cone's points lie on it (radius proportional to height), its apex row is one point with
// S_u = 0, and bad sizes are refused with the reason.
TEST(PrimitivesTest, ConeIsALinearProfileRevolvedWithItsApexAtTheOrigin) {
  const NurbsSurface cone = MakeCone(0.02, 0.04);
  double worst = 0.0;
  ForGrid(cone, 100, [&](double, double v, const SurfacePoint& p) {
    worst = std::max(worst, std::abs(p.S.head<2>().norm() - 0.5 * p.S.z()));
    EXPECT_NEAR(p.S.z(), 0.04 * v, 1e-16);
  });
  EXPECT_LE(worst, 1e-16);
  for (double u : {0.0, 0.3, 0.77}) {
    const SurfacePoint apex = cone.Evaluate(u, 0.0, 1);
    EXPECT_LE(apex.S.norm(), 1e-18);
    EXPECT_LE(apex.S_u.norm(), 1e-18);
    EXPECT_GT(apex.S_v.norm(), 0.04);
  }
  try {
    MakeCone(0.0, 0.04);
    ADD_FAILURE() << "a zero radius was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cone: radius and height must be positive"),
              std::string::npos);
  }
}

// Distance from a point in z = 0 to the paperclip's centre line, by brute force over the
// analytic segments (independent of the NURBS construction).
double DistanceToPath(const std::vector<PathSegment>& path, const Eigen::Vector2d& x) {
  Eigen::Vector2d pos = Eigen::Vector2d::Zero(), dir = Eigen::Vector2d::UnitY();
  double best = INFINITY;
  for (const PathSegment& seg : path) {
    if (seg.kind == PathSegment::Kind::kLine) {
      const Eigen::Vector2d end = pos + seg.length_or_radius * dir;
      const double t = std::clamp((x - pos).dot(dir), 0.0, seg.length_or_radius);
      best = std::min(best, (x - (pos + t * dir)).norm());
      pos = end;
    } else {
      const double r = seg.length_or_radius;
      const double sign = seg.angle > 0 ? 1.0 : -1.0;
      const Eigen::Vector2d c = pos + sign * r * Eigen::Vector2d(-dir.y(), dir.x());
      const double a0 = std::atan2(pos.y() - c.y(), pos.x() - c.x());
      const double a1 = a0 + seg.angle;
      // Inside the arc's angular range the nearest point is radial; otherwise an end point.
      const double ax = std::atan2(x.y() - c.y(), x.x() - c.x());
      double rel = std::remainder((ax - a0) * sign, 2 * std::numbers::pi);
      if (rel < 0) rel += 2 * std::numbers::pi;
      if (rel <= std::abs(seg.angle)) best = std::min(best, std::abs((x - c).norm() - r));
      for (double a : {a0, a1}) {
        best = std::min(best, (x - (c + r * Eigen::Vector2d(std::cos(a), std::sin(a)))).norm());
      }
      pos = c + r * Eigen::Vector2d(std::cos(a1), std::sin(a1));
      const double ct = std::cos(seg.angle), st = std::sin(seg.angle);
      dir = Eigen::Vector2d(ct * dir.x() - st * dir.y(), st * dir.x() + ct * dir.y());
    }
  }
  return best;
}

TEST(PrimitivesTest, PaperclipTubeIsAtWireRadiusFromItsCentreLine) {
  const auto path = PaperclipPath();
  const NurbsSurface clip = MakeTube(path, kPaperclipWireRadius);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  double worst = 0.0;
  ForGrid(clip, 300, [&](double, double, const SurfacePoint& p) {
    lo = lo.cwiseMin(p.S);
    hi = hi.cwiseMax(p.S);
    // The nearest centre-line point of a tube point is in its own cross-section plane, so the
    // distance to the centre line is the wire radius.
    const double in_plane = DistanceToPath(path, p.S.head<2>());
    worst = std::max(worst, std::abs(std::hypot(in_plane, p.S.z()) - kPaperclipWireRadius));
  });
  EXPECT_LT(worst, 1e-15);  // 0.45 mm radius: 1e-15 m is ~20 ulp of the 3 cm coordinates.
  EXPECT_NEAR(hi.y() - lo.y(), 33e-3, 0.5e-3);  // About 33 mm long ...
  EXPECT_NEAR(hi.z() - lo.z(), 0.9e-3, 1e-12);  // ... from wire 0.9 mm thick.
  EXPECT_NEAR(hi.x() - lo.x(), 8.9e-3, 0.1e-3);
}

TEST(PrimitivesTest, NormalsPointOutward) {
  // S_u × S_v points away from the centre (line) of every closed primitive, as primitives.h says.
  const NurbsSurface tube = MakeTube(PaperclipPath(), kPaperclipWireRadius);
  const NurbsSurface sphere = MakeSphere({0, 0, 0}, 0.05);
  const NurbsSurface cylinder = MakeCylinder(0.02, 0.1);
  const NurbsSurface torus = MakeTorus(0.05, 0.01);
  for (double u : {0.05, 0.2, 0.45, 0.7, 0.95}) {
    for (double v : {0.1, 0.3, 0.6, 0.85}) {
      const SurfacePoint t = tube.Evaluate(u, v, 1),
                         t2 = tube.Evaluate(u, std::fmod(v + 0.5, 1.0), 1);
      EXPECT_GT(t.S_u.cross(t.S_v).dot(t.S - 0.5 * (t.S + t2.S)), 0.0) << u << " " << v;
      const SurfacePoint s = sphere.Evaluate(u, v, 1);
      EXPECT_GT(s.S_u.cross(s.S_v).dot(s.S), 0.0);
      const SurfacePoint c = cylinder.Evaluate(u, v, 1);
      EXPECT_GT(c.S_u.cross(c.S_v).dot(Eigen::Vector3d(c.S.x(), c.S.y(), 0)), 0.0);
      const SurfacePoint r = torus.Evaluate(u, v, 1);
      const Eigen::Vector3d ring = 0.05 * Eigen::Vector3d(r.S.x(), r.S.y(), 0).normalized();
      EXPECT_GT(r.S_u.cross(r.S_v).dot(r.S - ring), 0.0);
    }
  }
}

TEST(PrimitivesTest, TubeRejectsBadPaths) {
  EXPECT_THROW(MakeTube({}, 1e-3), std::invalid_argument);
  EXPECT_THROW(MakeTube({PathSegment::Arc(0.5e-3, 1.0)}, 1e-3), std::invalid_argument);
  EXPECT_THROW(MakeTube({PathSegment::Line(-1.0)}, 1e-3), std::invalid_argument);
}

TEST(PrimitivesTest, ShearedPatchPartialsMeetAt10To20Degrees) {
  for (bool rational : {false, true}) {
    const NurbsSurface s = MakeShearedPatch(15.0 * std::numbers::pi / 180.0, 0.05, 0.004, rational);
    double lo = 180.0, hi = 0.0;
    ForGrid(s, 60, [&](double, double, const SurfacePoint& p) {
      const double c = p.S_u.normalized().dot(p.S_v.normalized());
      const double deg = std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / std::numbers::pi;
      lo = std::min(lo, deg);
      hi = std::max(hi, deg);
    });
    EXPECT_GE(lo, 10.0) << "rational=" << rational;
    EXPECT_LE(hi, 20.0) << "rational=" << rational;
  }
}

TEST(PrimitivesTest, HeightGridIsAGraphOverItsRectangle) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> h(-0.01, 0.01);
  std::vector<std::vector<double>> heights(6, std::vector<double>(7));
  for (auto& row : heights)
    for (double& z : row) z = h(rng);
  const NurbsSurface s = MakeHeightGridPatch(0.1, 0.2, 0.3, 0.4, heights);
  ForGrid(s, 50, [&](double u, double v, const SurfacePoint& p) {
    EXPECT_NEAR(p.S.x(), 0.1 + 0.3 * u, 1e-15);  // Greville placement: x, y linear in u, v.
    EXPECT_NEAR(p.S.y(), 0.2 + 0.4 * v, 1e-15);
  });
  EXPECT_THROW(MakeHeightGridPatch(0, 0, 1, 1, {{1, 2, 3}}), std::invalid_argument);
}

}  // namespace
}  // namespace tangent::nurbs
