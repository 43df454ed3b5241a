#pragma once

// Test configurations for contact: surfaces on bodies with seeded random poses, and helpers that
// place a pair separated, touching or interpenetrating along its extremal normal.

#include <random>

#include <Eigen/Geometry>

#include "contact/extremal.h"
#include "nurbs/primitives.h"

namespace tangent::contact::testing {

inline Vector7d Coordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

inline Eigen::Quaterniond RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

/// A rigid transform X applied to a pose: the whole scene moved (for frame-invariance checks).
inline Vector7d Transform(const Eigen::Isometry3d& x, const Vector7d& q) {
  const Eigen::Quaterniond rot(q[3], q[4], q[5], q[6]);
  return Coordinates(x * Eigen::Vector3d(q.head<3>()), Eigen::Quaterniond(x.rotation()) * rot);
}

/// Seed (u,v,s,t) of the closest pair over n x n grids on both surfaces (separated pairs).
inline Eigen::Vector4d ClosestGridPair(const nurbs::NurbsSurface& f, const BodyPose& pf,
                                       const nurbs::NurbsSurface& g, const BodyPose& pg, int n) {
  auto grid = [n](const nurbs::NurbsSurface& s, const BodyPose& p) {
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector3d>> pts;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const double u =
            s.knots_u().domain_begin() +
            (s.knots_u().domain_end() - s.knots_u().domain_begin()) * (i + 0.5) / (n + 1);
        const double v =
            s.knots_v().domain_begin() +
            (s.knots_v().domain_end() - s.knots_v().domain_begin()) * (j + 0.5) / (n + 1);
        pts.push_back({{u, v}, p.Point(s.Evaluate(u, v, 0).S)});
      }
    }
    return pts;
  };
  const auto a = grid(f, pf), b = grid(g, pg);
  double best = INFINITY;
  Eigen::Vector4d seed;
  for (const auto& x : a) {
    for (const auto& y : b) {
      const double d = (x.second - y.second).squaredNorm();
      if (d < best) {
        best = d;
        seed << x.first, y.first;
      }
    }
  }
  return seed;
}

/// A surface pair on two bodies.
struct Pair {
  const char* name;
  nurbs::NurbsSurface f, g;
  Vector7d q_f, q_g;
};

/// Moves body G along n_g so the extremal distance becomes `target_beta` (to first order; then
/// re-solved by the caller). Returns the new q_g.
inline Vector7d ShiftToBeta(const SurfaceSurfaceExtremum& e, const Vector7d& q_g,
                            double target_beta) {
  Vector7d q = q_g;
  q.head<3>() += (e.beta - target_beta) * e.n_g;
  return q;
}

}  // namespace tangent::contact::testing
