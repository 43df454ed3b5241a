#pragma once

// Seeded random NURBS for tests and benchmarks: non-uniform knots, clamped or not, positive
// weights. Every generator takes the engine explicitly so each test states its seed.

#include <random>
#include <vector>

#include "nurbs/curve.h"
#include "nurbs/surface.h"

namespace tangent::nurbs::testing {

/// A knot vector of degree p with n basis functions, random non-uniform interior spacing (span
/// lengths vary by up to 10x), optionally with a repeated interior knot and unclamped ends.
inline KnotVector RandomKnots(std::mt19937_64& rng, int p, int n, bool clamped,
                              bool allow_repeats = true) {
  std::uniform_real_distribution<double> len(0.1, 1.0);
  std::vector<double> k;
  const int total = n + p + 1;
  double t = -0.37;  // An offset so the domain is not [0, 1].
  if (clamped) {
    for (int i = 0; i <= p; ++i) k.push_back(t);
    for (int i = 0; i < n - p - 1; ++i) {
      t += len(rng);
      k.push_back(t);
      if (allow_repeats && p >= 2 && i == 0 && n - p - 1 >= 3 && static_cast<int>(k.size()) < n) {
        k.push_back(t);  // One double interior knot (C^{p-2} there).
        ++i;
      }
    }
    t += len(rng);
    while (static_cast<int>(k.size()) < total) k.push_back(t);
  } else {
    for (int i = 0; i < total; ++i) {
      k.push_back(t);
      t += len(rng);
    }
  }
  return KnotVector(p, std::move(k));
}

/// A gently curved random sheet on the given knot vectors (their basis counts set the net).
inline NurbsSurface RandomSheet(std::mt19937_64& rng, KnotVector ku, KnotVector kv, bool rational) {
  const int nu = ku.num_basis(), nv = kv.num_basis();
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  std::uniform_real_distribution<double> weight(0.5, 2.0);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      // A gently curved sheet plus noise, so the surface is not a random tangle.
      pts.emplace_back(i + 0.3 * coord(rng), j + 0.3 * coord(rng), 0.5 * coord(rng));
      if (rational) w.push_back(weight(rng));
    }
  }
  return NurbsSurface(std::move(ku), std::move(kv), pts, w);
}

inline NurbsSurface RandomSurface(std::mt19937_64& rng, int p, int q, int nu, int nv, bool rational,
                                  bool clamped = true) {
  KnotVector ku = RandomKnots(rng, p, nu, clamped);
  KnotVector kv = RandomKnots(rng, q, nv, clamped);
  return RandomSheet(rng, std::move(ku), std::move(kv), rational);
}

template <int Dim>
NurbsCurve<Dim> RandomCurve(std::mt19937_64& rng, int p, int n, bool rational,
                            bool clamped = true) {
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  std::uniform_real_distribution<double> weight(0.5, 2.0);
  KnotVector k = RandomKnots(rng, p, n, clamped);
  std::vector<Eigen::Matrix<double, Dim, 1>> pts;
  std::vector<double> w;
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<double, Dim, 1> x;
    for (int d = 0; d < Dim; ++d) x[d] = coord(rng);
    x[0] += i;
    pts.push_back(x);
    if (rational) w.push_back(weight(rng));
  }
  return NurbsCurve<Dim>(std::move(k), pts, w);
}

/// A uniformly random parameter in the domain of a knot vector.
inline double RandomParam(std::mt19937_64& rng, const KnotVector& k) {
  return std::uniform_real_distribution<double>(k.domain_begin(), k.domain_end())(rng);
}

}  // namespace tangent::nurbs::testing
