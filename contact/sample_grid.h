#pragma once

// A placed surface sampled on an even grid over a parameter box (internal header): the closest
// sample pair seeds of ClosestSamplePair (the whole domain, contact/closest_pair.cc) and of the
// neighbourhood search (a window of it, contact/neighbourhood.cc). The points are stored by the
// caller, so a fixed-size array keeps the search allocation free.

#include <Eigen/Core>
#include <limits>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::contact::internal {

/// (n+1)² points over [lo, hi], index i·(n+1) + j (u step i, v step j), edges included.
struct SampleGrid {
  int n = 0;
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();
  Eigen::Vector3d* x = nullptr;  ///< (n+1)² points, the caller's storage

  Eigen::Vector2d Uv(int i, int j) const {
    return {lo[0] + (hi[0] - lo[0]) * i / n, lo[1] + (hi[1] - lo[1]) * j / n};
  }
  const Eigen::Vector3d& At(int i, int j) const { return x[i * (n + 1) + j]; }
  /// Evaluates the placed surface at every grid point.
  void Sample(const nurbs::NurbsSurface& s, const BodyPose& pose) {
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const Eigen::Vector2d uv = Uv(i, j);
        x[i * (n + 1) + j] = pose.Point(s.Evaluate(uv[0], uv[1], 0).S);
      }
    }
  }
};

/// The sample of `g` closest to p: its squared distance and (i, j).
inline double ClosestSample(const SampleGrid& g, const Eigen::Vector3d& p, int* bi, int* bj) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= g.n; ++i) {
    for (int j = 0; j <= g.n; ++j) {
      const double d = (g.At(i, j) - p).squaredNorm();
      if (d < best) {
        best = d;
        *bi = i;
        *bj = j;
      }
    }
  }
  return best;
}

/// The box's four edges: 0 v = lo and 1 v = hi (running along u), 2 u = lo and 3 u = hi.
inline bool EdgeAlongU(int edge) { return edge < 2; }
inline bool EdgeHigh(int edge) { return edge % 2 == 1; }

/// (i, j) of sample k ∈ [0, n] along edge `edge` of an n-step grid.
inline void EdgeSample(int n, int edge, int k, int* i, int* j) {
  const int held = EdgeHigh(edge) ? n : 0;
  *i = EdgeAlongU(edge) ? k : held;
  *j = EdgeAlongU(edge) ? held : k;
}

}  // namespace tangent::contact::internal
