#pragma once

// Surface pairs whose closest points lie on a domain edge or corner (issue 38), and a dense
// sampling truth of their closest pair that knows nothing of our solvers: shared by
// BoundaryMinimaTest and contact_bench's boundary section.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "contact/placed.h"
#include "nurbs/surface.h"
#include "testing/random_nurbs.h"

namespace tangent::contact::testing {

using nurbs::NurbsSurface;

inline Vector7d PoseCoordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

inline Eigen::Vector2d Lo(const NurbsSurface& s) {
  return {s.knots_u().domain_begin(), s.knots_v().domain_begin()};
}
inline Eigen::Vector2d Hi(const NurbsSurface& s) {
  return {s.knots_u().domain_end(), s.knots_v().domain_end()};
}

// Points of a placed surface on an (n+1)² grid over [lo, hi] (a window of the domain).
struct Grid {
  std::vector<Eigen::Vector2d> uv;
  std::vector<Eigen::Vector3d> x;
};
inline Grid Sample(const NurbsSurface& s, const BodyPose& pose, const Eigen::Vector2d& lo,
                   const Eigen::Vector2d& hi, int n) {
  Grid g;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const Eigen::Vector2d uv(lo[0] + (hi[0] - lo[0]) * i / n, lo[1] + (hi[1] - lo[1]) * j / n);
      g.uv.push_back(uv);
      g.x.push_back(pose.Point(s.Evaluate(uv[0], uv[1], 0).S));
    }
  }
  return g;
}

// Dense sampling truth of the closest pair: a 64² grid per surface (edges and corners
// included), then a 40² grid per surface on a window of ±2 coarse cells around the best pair.
// Its distance is an upper bound of the true minimum within ~1e-4 of it.
struct Truth {
  Eigen::Vector4d u;
  double distance;
};
inline Truth SampledClosestPair(const NurbsSurface& f, const BodyPose& pf, const NurbsSurface& g,
                                const BodyPose& pg) {
  auto best_of = [](const Grid& a, const Grid& b) {
    Truth t{Eigen::Vector4d::Zero(), std::numeric_limits<double>::infinity()};
    for (size_t i = 0; i < a.x.size(); ++i) {
      for (size_t j = 0; j < b.x.size(); ++j) {
        const double d = (a.x[i] - b.x[j]).squaredNorm();
        if (d < t.distance)
          t = {Eigen::Vector4d(a.uv[i][0], a.uv[i][1], b.uv[j][0], b.uv[j][1]), d};
      }
    }
    t.distance = std::sqrt(t.distance);
    return t;
  };
  constexpr int kCoarse = 64, kFine = 40;
  const Truth coarse =
      best_of(Sample(f, pf, Lo(f), Hi(f), kCoarse), Sample(g, pg, Lo(g), Hi(g), kCoarse));
  auto window = [&](const NurbsSurface& s, const Eigen::Vector2d& at, Eigen::Vector2d* lo,
                    Eigen::Vector2d* hi) {
    const Eigen::Vector2d cell = (Hi(s) - Lo(s)) / kCoarse;
    *lo = (at - 2.0 * cell).cwiseMax(Lo(s));
    *hi = (at + 2.0 * cell).cwiseMin(Hi(s));
  };
  Eigen::Vector2d flo, fhi, glo, ghi;
  window(f, coarse.u.head<2>(), &flo, &fhi);
  window(g, coarse.u.tail<2>(), &glo, &ghi);
  const Truth fine = best_of(Sample(f, pf, flo, fhi, kFine), Sample(g, pg, glo, ghi, kFine));
  return fine.distance < coarse.distance ? fine : coarse;
}

enum class Layout { kCornerFace, kEdgeFace, kEdgeEdge };

// Two random rational bicubic sheets (about 4 x 4 x 1 units, curved) posed so that the closest
// points lie on a boundary of one or both.
struct Case {
  NurbsSurface f, g;
  BodyPose pf, pg;
};
inline Case Place(std::mt19937_64& rng, Layout layout, NurbsSurface f, NurbsSurface g) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const BodyPose pg =
      BodyPose::FromCoordinates(PoseCoordinates({0, 0, 0}, Eigen::Quaterniond::Identity()));
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  switch (layout) {
    case Layout::kCornerFace:  // f tipped on a corner above g's middle
      q = Eigen::AngleAxisd(0.5 + 0.3 * uni(rng), Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(-0.5 - 0.3 * uni(rng), Eigen::Vector3d::UnitY());
      p = {1.5 + uni(rng), 1.5 + uni(rng), 1.2 + 0.5 * uni(rng)};
      break;
    case Layout::kEdgeFace:  // f tilted about one edge's direction only, above g
      q = Eigen::AngleAxisd(0.6 + 0.4 * uni(rng), Eigen::Vector3d::UnitX());
      p = {0.5 * uni(rng), 1.5 + uni(rng), 1.2 + 0.5 * uni(rng)};
      break;
    case Layout::kEdgeEdge:  // f beside g, turned and tilted so their near edges cross
      q = Eigen::AngleAxisd(-0.4 - 0.5 * uni(rng), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.3 + 0.6 * uni(rng), Eigen::Vector3d::UnitY());
      p = {5.0 + uni(rng), -1.0 + 2.0 * uni(rng), 0.5 * uni(rng)};
      break;
  }
  return {std::move(f), std::move(g), BodyPose::FromCoordinates(PoseCoordinates(p, q)), pg};
}
// A random sheet of degree p in both directions, rational or not, about 4 x 4 x 1 units
// whatever its degree: max(5, p + 1) control points a side on random non-uniform knots, and a
// single bilinear patch for p = 1 (several would meet at creases, where no smooth minimum is).
inline NurbsSurface Sheet(std::mt19937_64& rng, int p, bool rational) {
  const int n = p == 1 ? 2 : std::max(5, p + 1);
  nurbs::KnotVector ku = nurbs::testing::RandomKnots(rng, p, n, true);
  nurbs::KnotVector kv = nurbs::testing::RandomKnots(rng, p, n, true);
  std::uniform_real_distribution<double> coord(-1.0, 1.0), weight(0.5, 2.0);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  const double step = 4.0 / (n - 1);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      pts.emplace_back(step * (i + 0.3 * coord(rng)), step * (j + 0.3 * coord(rng)),
                       0.5 * coord(rng));
      if (rational) w.push_back(weight(rng));
    }
  }
  return NurbsSurface(std::move(ku), std::move(kv), pts, w);
}

}  // namespace tangent::contact::testing
