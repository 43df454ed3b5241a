#pragma once

// A surface the global contact stage watches (global.cc): its offset mesh's blocks and their
// world boxes, its trim edges, and the arc-length metric of its parameter domain (through its
// pole rows) that the spheres of neglect measure with. Internal to tangent_contact (it includes
// FCL). Split from global.cc by concept.

#include <fcl/fcl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "contact/global.h"
#include "contact/global_minima.h"
#include "contact/offset_chunks.h"
#include "contact/trimmed.h"

namespace tangent::contact::internal {

struct Watched {
  GlobalSurface s;
  std::unique_ptr<TrimEdges> edges;  // when trimmed
  std::vector<Chunk> chunks;
  // The whole offset mesh's box (surface frame) as an FCL box: the object the broad-phase
  // manager sees.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), half = Eigen::Vector3d::Zero();
  std::unique_ptr<fcl::CollisionObjectd> object;
  std::vector<WorldBox> placed;  // chunks' world boxes (placed on demand, once a pass)
  std::vector<int> placed_at;    // the pass each chunk's world box was placed in (-1: none)
  double L_u = 1.0, L_v = 1.0;   // mean |S_u|, |S_v|: metres per parameter unit
  double w_u = 1.0, w_v = 1.0;   // domain widths
  bool periodic_u = false, periodic_v = false;

  // Pole rows (a domain edge collapsed to one point: a sphere's or a revolved part's apex):
  // [0] u = u_lo, [1] u = u_hi (S_v vanishes along them), [2] v = v_lo, [3] v = v_hi (S_u).
  std::array<bool, 4> pole{};
  double u_lo = 0.0, v_lo = 0.0;

  // Arc-length distance from a parameter point to the farthest corner of a chunk's box, i.e. an
  // upper bound of Along(x, y) over the chunk's points y (each path's own maximum over the
  // corners: min(f, g) ≤ min(max f, max g)).
  double FarthestAlong(const Eigen::Vector2d& x, const Chunk& c) const {
    double direct = 0.0;
    std::array<double, 4> via{};
    for (double u : {c.uv_lo[0], c.uv_hi[0]}) {
      for (double v : {c.uv_lo[1], c.uv_hi[1]}) {
        const Eigen::Vector2d y(u, v);
        direct = std::max(direct, Direct(x, y));
        for (int k = 0; k < 4; ++k) via[k] = std::max(via[k], ViaPole(k, x, y));
      }
    }
    return std::min(direct, *std::min_element(via.begin(), via.end()));
  }
  // Arc-length distance between two parameter points (periodic directions wrap): along the
  // parameter lines, or through a pole (moving along a pole row costs nothing, so two points
  // near an apex are near each other whatever their angles).
  double Along(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    double best = Direct(a, b);
    for (int k = 0; k < 4; ++k) best = std::min(best, ViaPole(k, a, b));
    return best;
  }
  double Direct(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    double du = std::abs(a[0] - b[0]), dv = std::abs(a[1] - b[1]);
    if (periodic_u) du = std::min(du, w_u - du);
    if (periodic_v) dv = std::min(dv, w_v - dv);
    return du * L_u + dv * L_v;
  }
  // To pole row k and along it to b (+inf without that pole).
  double ViaPole(int k, const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    if (!pole[static_cast<size_t>(k)]) return std::numeric_limits<double>::infinity();
    const int across = k < 2 ? 0 : 1;
    const double bound = across == 0 ? (k == 0 ? u_lo : u_lo + w_u) : (k == 2 ? v_lo : v_lo + w_v);
    const double L = across == 0 ? L_u : L_v;
    return (std::abs(a[across] - bound) + std::abs(b[across] - bound)) * L;
  }
};

}  // namespace tangent::contact::internal
