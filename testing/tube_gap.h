#pragma once

// Ground truth for scenes of wires (tubes of a circular section swept along a path: the
// paperclips, nurbs::MakeTube; rings, nurbs::MakeTorus): the gap between two wires is the least
// distance between their centre lines less both radii, wherever a wire does not bend tighter than
// its radius. It needs nothing of the contact code it checks: each centre line is sampled from
// the surface (the midpoint of two antipodal points of a section) as a polyline in its body's
// frame, and two placed polylines' least distance is found coarse to fine.

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "nurbs/surface.h"

namespace tangent::testing {

/// A wire's centre line in its body's frame, `samples` points along `along` (0: u, 1: v), and
/// its radius (the mean of the sections').
struct Centreline {
  std::vector<Eigen::Vector3d> points;
  double radius = 0.0;
};

inline Centreline SampleCentreline(const nurbs::NurbsSurface& s, int along, int samples) {
  const nurbs::KnotVector& ka = along == 0 ? s.knots_u() : s.knots_v();
  const nurbs::KnotVector& kr = along == 0 ? s.knots_v() : s.knots_u();
  const double r0 = kr.domain_begin(), half = 0.5 * (kr.domain_end() - kr.domain_begin());
  Centreline c;
  for (int i = 0; i < samples; ++i) {
    const double a = ka.domain_begin() + (ka.domain_end() - ka.domain_begin()) * i / (samples - 1);
    auto at = [&](double r) { return along == 0 ? s.Evaluate(a, r, 0).S : s.Evaluate(r, a, 0).S; };
    const Eigen::Vector3d p = at(r0), q = at(r0 + half);
    c.points.push_back(0.5 * (p + q));
    c.radius += 0.5 * (p - q).norm() / samples;
  }
  return c;
}

/// The least distance between segments [p0, p1] and [q0, q1].
inline double SegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                              const Eigen::Vector3d& q0, const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= 1e-300 && e <= 1e-300) return r.norm();
  if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 0.0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p0 + s * d1 - q0 - t * d2).norm();
}

/// The least distance between two centre lines placed in the world by (R, p) each: segment
/// pairs of a coarse polyline (every `stride`-th point) within 2 mm of the least, then the fine
/// segments inside them. *at_a, *at_b (when given): the first points of the closest fine
/// segments, indices into a.points and b.points.
inline double CentrelineDistance(const Centreline& a, const Eigen::Matrix3d& Ra,
                                 const Eigen::Vector3d& pa, const Centreline& b,
                                 const Eigen::Matrix3d& Rb, const Eigen::Vector3d& pb,
                                 int stride = 16, int* at_a = nullptr, int* at_b = nullptr) {
  std::vector<Eigen::Vector3d> wa(a.points.size()), wb(b.points.size());
  for (size_t i = 0; i < wa.size(); ++i) wa[i] = Ra * a.points[i] + pa;
  for (size_t j = 0; j < wb.size(); ++j) wb[j] = Rb * b.points[j] + pb;
  const int na = static_cast<int>(wa.size()), nb = static_cast<int>(wb.size());
  struct Pair {
    int i, j;
    double d;
  };
  std::vector<Pair> coarse;
  double least = INFINITY;
  for (int i = 0; i + 1 < na; i += stride) {
    const int i1 = std::min(i + stride, na - 1);
    for (int j = 0; j + 1 < nb; j += stride) {
      const int j1 = std::min(j + stride, nb - 1);
      const double d = SegmentDistance(wa[i], wa[i1], wb[j], wb[j1]);
      coarse.push_back({i, j, d});
      least = std::min(least, d);
    }
  }
  double best = INFINITY;
  for (const Pair& c : coarse) {
    if (c.d > least + 2e-3) continue;
    for (int i = c.i; i < std::min(c.i + stride, na - 1); ++i) {
      for (int j = c.j; j < std::min(c.j + stride, nb - 1); ++j) {
        const double d = SegmentDistance(wa[i], wa[i + 1], wb[j], wb[j + 1]);
        if (d < best) {
          best = d;
          if (at_a) *at_a = i;
          if (at_b) *at_b = j;
        }
      }
    }
  }
  return best;
}

}  // namespace tangent::testing
