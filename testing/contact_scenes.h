#pragma once

// Test configurations for contact: surfaces on bodies with seeded random poses, and helpers that
// place a pair separated, touching or interpenetrating along its extremal normal.

#include <random>
#include <vector>

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

/// The paraboloid z = k (x² + y²)/2 over [−a, a]², exact as a biquadratic Bézier patch (the
/// blossom of x² gives control heights a², −a², a²). Radius of curvature at the vertex: 1/k;
/// its focal point is at height 1/k (design.md §4.3's focal-point case).
inline nurbs::NurbsSurface Paraboloid(double k, double a) {
  const double xs[3] = {-a, 0, a}, x2[3] = {a * a, -a * a, a * a};
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) pts.emplace_back(xs[i], xs[j], 0.5 * k * (x2[i] + x2[j]));
  return nurbs::NurbsSurface(nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}),
                             nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}), pts);
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
