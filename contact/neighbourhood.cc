#include "contact/neighbourhood.h"

#include <algorithm>
#include <limits>

namespace tangent::contact::internal {

namespace {

constexpr int kSide = kWindowSamples + 1;

/// One surface's window: its parameter box and world points on an even grid over it.
struct Window {
  Eigen::Vector2d lo, hi;
  /// Which domain edges the window reaches: [v = lo, v = hi, u = lo, u = hi].
  std::array<bool, 4> edge{};
  std::array<Eigen::Vector3d, kSide * kSide> x;  ///< index i·kSide + j (u step i, v step j)
  Eigen::Vector2d Uv(int i, int j) const {
    return {lo[0] + (hi[0] - lo[0]) * i / kWindowSamples,
            lo[1] + (hi[1] - lo[1]) * j / kWindowSamples};
  }
  const Eigen::Vector3d& At(int i, int j) const { return x[static_cast<size_t>(i * kSide + j)]; }
};

/// Whether the domain edge where parameter d is held at `bound` collapses to a point (a pole
/// row: the derivative along it vanishes). It is not an edge of the surface but one point of
/// it, which the solver's pole handling answers for.
bool IsPoleRow(const nurbs::NurbsSurface& s, int d, double bound, const Eigen::Vector2d& at) {
  Eigen::Vector2d uv = at;
  uv[d] = bound;
  const nurbs::SurfacePoint p = s.Evaluate(uv[0], uv[1], 1);
  const Eigen::Vector3d& along = d == 1 ? p.S_u : p.S_v;
  const Eigen::Vector3d& across = d == 1 ? p.S_v : p.S_u;
  return across.norm() > 0.0 && along.norm() <= nurbs::kDegenerateRatio * across.norm();
}

/// The window's box and the edges it reaches (a periodic direction has none: its ends are a
/// seam, and its window is clamped to one period; nor has a pole row).
void Bound(const nurbs::NurbsSurface& s, const Eigen::Vector2d& at, double radius, Window* w) {
  const nurbs::KnotVector* k[2] = {&s.knots_u(), &s.knots_v()};
  const bool periodic[2] = {s.periodic_u(), s.periodic_v()};
  for (int d = 0; d < 2; ++d) {
    const double a = k[d]->domain_begin(), b = k[d]->domain_end(), r = radius * (b - a);
    w->lo[d] = std::max(a, at[d] - r);
    w->hi[d] = std::min(b, at[d] + r);
    // edge index: d = 1 (v held) → 0, 1; d = 0 (u held) → 2, 3
    const int e = d == 1 ? 0 : 2;
    w->edge[static_cast<size_t>(e)] = !periodic[d] && w->lo[d] <= a && !IsPoleRow(s, d, a, at);
    w->edge[static_cast<size_t>(e + 1)] = !periodic[d] && w->hi[d] >= b && !IsPoleRow(s, d, b, at);
  }
}

void Sample(const nurbs::NurbsSurface& s, const BodyPose& pose, Window* w) {
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      const Eigen::Vector2d uv = w->Uv(i, j);
      w->x[static_cast<size_t>(i * kSide + j)] = pose.Point(s.Evaluate(uv[0], uv[1], 0).S);
    }
  }
}

/// (i, j) of sample k along edge e of a window (the window's border row on that edge).
void EdgeSample(int e, int k, int* i, int* j) {
  const bool along_u = e < 2, high = e % 2 == 1;
  *i = along_u ? k : (high ? kWindowSamples : 0);
  *j = along_u ? (high ? kWindowSamples : 0) : k;
}

/// The sample of window b closest to x: its squared distance and (i, j).
double ClosestTo(const Window& b, const Eigen::Vector3d& x, int* bi, int* bj) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      const double d = (b.At(i, j) - x).squaredNorm();
      if (d < best) {
        best = d;
        *bi = i;
        *bj = j;
      }
    }
  }
  return best;
}

/// The closest pair of a's samples on edge e against b's window, as the pair's parameters (a
/// first when a_is_f).
Eigen::Vector4d ClosestPair(const Window& a, int e, const Window& b, bool a_is_f) {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d on_a = a.lo, on_b = b.lo;
  for (int k = 0; k < kSide; ++k) {
    int i = 0, j = 0, bi = 0, bj = 0;
    EdgeSample(e, k, &i, &j);
    const double d = ClosestTo(b, a.At(i, j), &bi, &bj);
    if (d < best) {
      best = d;
      on_a = a.Uv(i, j);
      on_b = b.Uv(bi, bj);
    }
  }
  Eigen::Vector4d u;
  if (a_is_f) {
    u << on_a, on_b;
  } else {
    u << on_b, on_a;
  }
  return u;
}

}  // namespace

bool NeighbourhoodReachesBoundary(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                                  const Eigen::Vector4d& seed, double radius) {
  Window wf, wg;
  Bound(f, seed.head<2>(), radius, &wf);
  Bound(g, seed.tail<2>(), radius, &wg);
  auto any = [](const std::array<bool, 4>& a) { return a[0] || a[1] || a[2] || a[3]; };
  return any(wf.edge) || any(wg.edge);
}

void FindNeighbourhoodStarts(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                             const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                             const Eigen::Vector4d& seed, double radius, NeighbourhoodStarts* out) {
  out->n = 0;
  Window wf, wg;
  Bound(f, seed.head<2>(), radius, &wf);
  Bound(g, seed.tail<2>(), radius, &wg);
  Sample(f, pose_f, &wf);
  Sample(g, pose_g, &wg);
  // A start found twice (a corner sample is on two edges) is solved once.
  auto add = [out](const Eigen::Vector4d& u) {
    for (int k = 0; k < out->n; ++k) {
      if (out->u[static_cast<size_t>(k)] == u) return;
    }
    out->u[static_cast<size_t>(out->n++)] = u;
  };
  for (int e = 0; e < 4; ++e) {
    if (wf.edge[static_cast<size_t>(e)]) add(ClosestPair(wf, e, wg, /*a_is_f=*/true));
    if (wg.edge[static_cast<size_t>(e)]) add(ClosestPair(wg, e, wf, /*a_is_f=*/false));
  }
}

}  // namespace tangent::contact::internal
