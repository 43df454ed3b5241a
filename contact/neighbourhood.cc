#include "contact/neighbourhood.h"

#include <algorithm>
#include <limits>

#include "contact/poles.h"
#include "contact/sample_grid.h"

namespace tangent::contact::internal {

namespace {

constexpr int kSide = kWindowSamples + 1;

/// One surface's window: its parameter box and world points on an even grid over it.
struct Window {
  std::array<Eigen::Vector3d, kSide * kSide> points;
  SampleGrid grid{kWindowSamples, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), points.data()};
  /// Which domain edges the window reaches (SampleGrid's edge numbering).
  std::array<bool, 4> edge{};
  Window() = default;
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
};

/// The window's box and the edges it reaches (a periodic direction has none: its ends are a
/// seam, and its window is clamped to one period; nor has a pole row).
void Bound(const nurbs::NurbsSurface& s, const Eigen::Vector2d& at, double radius, Window* w) {
  const nurbs::KnotVector* k[2] = {&s.knots_u(), &s.knots_v()};
  const bool periodic[2] = {s.periodic_u(), s.periodic_v()};
  for (int d = 0; d < 2; ++d) {
    const double a = k[d]->domain_begin(), b = k[d]->domain_end(), r = radius * (b - a);
    w->grid.lo[d] = std::max(a, at[d] - r);
    w->grid.hi[d] = std::min(b, at[d] + r);
    const int e = d == 1 ? 0 : 2;  // SampleGrid's edges: v held (d = 1) 0, 1; u held 2, 3
    w->edge[static_cast<size_t>(e)] =
        !periodic[d] && w->grid.lo[d] <= a && !IsPoleRowAt(s, d, a, at);
    w->edge[static_cast<size_t>(e + 1)] =
        !periodic[d] && w->grid.hi[d] >= b && !IsPoleRowAt(s, d, b, at);
  }
}

/// The closest pair of a's samples on edge e against b's window, as the pair's parameters (a
/// first when a_is_f).
Eigen::Vector4d ClosestPair(const Window& a, int e, const Window& b, bool a_is_f) {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d on_a = a.grid.lo, on_b = b.grid.lo;
  for (int k = 0; k < kSide; ++k) {
    int i = 0, j = 0, bi = 0, bj = 0;
    EdgeSample(kWindowSamples, e, k, &i, &j);
    const double d = ClosestSample(b.grid, a.grid.At(i, j), &bi, &bj);
    if (d < best) {
      best = d;
      on_a = a.grid.Uv(i, j);
      on_b = b.grid.Uv(bi, bj);
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

void FindNeighbourhoodStarts(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                             const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                             const Eigen::Vector4d& seed, double radius, NeighbourhoodStarts* out) {
  out->n = 0;
  Window wf, wg;
  Bound(f, seed.head<2>(), radius, &wf);
  Bound(g, seed.tail<2>(), radius, &wg);
  auto any = [](const std::array<bool, 4>& a) { return a[0] || a[1] || a[2] || a[3]; };
  if (!any(wf.edge) && !any(wg.edge)) return;  // no boundary within reach: nothing sampled
  wf.grid.Sample(f, pose_f);
  wg.grid.Sample(g, pose_g);
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
