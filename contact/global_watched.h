#pragma once

// A surface the global contact stage watches (global.cc): its offset mesh's blocks and their
// world boxes, its trim edges or its corners (a flat face), and the arc-length metric of its
// parameter domain (through its pole rows) that the spheres of neglect measure with; and the
// stage's own data (GlobalContactStage::Impl), shared by global.cc and global_conformal.cc.
// Internal to tangent_contact (it includes FCL). Split from global.cc by concept.

#include <fcl/fcl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "contact/global.h"
#include "contact/global_minima.h"
#include "contact/offset_chunks.h"
#include "contact/trimmed.h"
#include "nurbs/flat.h"

namespace tangent::contact::internal {

struct Watched {
  GlobalSurface s;
  std::unique_ptr<TrimEdges> edges;     // when trimmed
  std::optional<nurbs::FlatQuad> flat;  // when a flat quadrilateral face, untrimmed (face_gap.h)
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

// A seed of the narrow phase, with the cluster neglected in its favour (global.cc).
struct Seed {
  Eigen::Vector4d u;
  Eigen::Vector3d x;  // where the offset meshes met (world)
  // The cluster of seeds neglected in its favour: parameter sums (periodic directions as unit
  // vectors on the circle), for the cluster's mean.
  Eigen::Vector4d sum = Eigen::Vector4d::Zero(), sum_cos = Eigen::Vector4d::Zero(),
                  sum_sin = Eigen::Vector4d::Zero();
  int count = 0;
  // A few members kept as fallback seeds (the 2nd, 8th, 32nd, 128th of the cluster).
  std::array<Eigen::Vector4d, 4> members{Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(),
                                         Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero()};
  int n_members = 0;
};

// World box of a surface-frame box (centre c, half extents h) under pose p: exact for the box.
inline WorldBox Place(const BodyPose& p, const Eigen::Vector3d& c, const Eigen::Vector3d& h) {
  const Eigen::Vector3d centre = p.Point(c);
  const Eigen::Vector3d e = p.R_WB.cwiseAbs() * h;
  return {centre - e, centre + e};
}

}  // namespace tangent::contact::internal

namespace tangent::contact {

// The stage's own data: the watched surfaces, the declarations, the broad phase and each
// pass's workspace (global.cc; the conformal finders in global_conformal.cc).
struct GlobalContactStage::Impl {
  std::vector<internal::Watched> watched;
  // The declared pairs: surface pairs (a < b, sorted) and body pairs (num_bodies²): memory grows
  // with the declarations and the bodies, not with the faces' pairs.
  std::vector<std::pair<int, int>> surface_declared;
  std::vector<char> body_declared;
  int num_bodies = 0;
  std::unique_ptr<fcl::BroadPhaseCollisionManagerd> manager;
  // Surface pairs the broad phase reported (a < b), then the chunk pairs of each whose world
  // boxes overlap: (surface a, surface b, chunk of a, chunk of b).
  std::vector<std::pair<int, int>> surface_pairs;
  std::vector<std::array<int, 4>> candidates;
  std::vector<int> near_a, near_b;
  // Per surface pair in FindContacts (kept to reuse their storage): the seeds accepted (tracked
  // contacts first, then clusters) and the offset-triangle pairs of the narrow phase.
  std::vector<internal::Seed> accepted;
  std::vector<std::pair<int, int>> triangle_pairs;
  // The surface pairs whose offsets crossed this pass (FindNested skips them).
  std::vector<std::pair<int, int>> crossed;
  int n = 0, pass = 0;
  bool Allowed(int a, int b) const {
    const int ba = watched[static_cast<size_t>(a)].s.body,
              bb = watched[static_cast<size_t>(b)].s.body;
    if (body_declared[static_cast<size_t>(ba * num_bodies + bb)]) return true;
    return std::binary_search(surface_declared.begin(), surface_declared.end(),
                              std::make_pair(std::min(a, b), std::max(a, b)));
  }
  /// A declared surface pair (a < b) of two flat faces: held by their corners (FindFaces), not
  /// by the narrow phase's extrema.
  bool FacePair(int a, int b) const {
    return watched[static_cast<size_t>(a)].flat && watched[static_cast<size_t>(b)].flat &&
           std::binary_search(surface_declared.begin(), surface_declared.end(),
                              std::make_pair(a, b));
  }
};

}  // namespace tangent::contact
