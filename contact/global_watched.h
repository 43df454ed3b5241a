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
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <unsupported/Eigen/BVH>

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
  // The chunks' boxes (surface frame) in a bounding-volume tree, built when the surface is
  // watched: the broad phase asks it which chunks lie near another surface's box.
  std::unique_ptr<Eigen::KdBVH<double, 3, int>> chunk_tree;
  // The whole offset mesh's box (surface frame) as an FCL box: the object the broad-phase
  // manager sees.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), half = Eigen::Vector3d::Zero();
  std::unique_ptr<fcl::CollisionObjectd> object;
  std::vector<WorldBox> placed;  // chunks' world boxes (placed on demand, once a pass)
  std::vector<int> placed_at;    // the pass each chunk's world box was placed in (-1: none)
  // Per chunk, which of the current surface pair's centres of neglect lie within far_factor x ρ
  // of all of it (global_seeds.cc, NearACentre): bit i for centre i, valid for the search
  // `near_search` and its first `near_upto` centres (later centres are added as they come).
  std::vector<uint64_t> near_mask;
  std::vector<int> near_search;
  std::vector<int> near_upto;
  double L_u = 1.0, L_v = 1.0;  // mean |S_u|, |S_v|: metres per parameter unit
  double w_u = 1.0, w_v = 1.0;  // domain widths
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
  // Refinement (global_seeds.cc): done once it reached a contact, a near miss or its own
  // minimum apart, or ran out of seeds to try; `tried`: its count when its mean was solved from.
  bool done = false;
  int tried = 0;
};

// Where a surface pair's spheres of neglect are centred in a pass (global.cc): its tracked
// contacts and its near misses re-solved (global_misses.cc), by their parameters and the
// midpoint of their two points (world).
struct Centre {
  Eigen::Vector4d u;
  Eigen::Vector3d x;
};

// A near miss of surfaces a < b (global_misses.cc): a minimum of their distance that a
// refinement reached apart, activation ≤ β < the offsets' reach, by its parameters.
struct NearMiss {
  int a = -1, b = -1;
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
};
// A near miss re-solved in this pass's poses, with the pair's evaluation there.
struct Revived {
  SurfaceSurfaceExtremum e;
  SurfacePairEval at;
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
  // The pair's centres of neglect in FindContacts; the near misses the last pass kept, and
  // those this pass keeps (global_misses.cc).
  std::vector<internal::Centre> centres;
  std::vector<internal::NearMiss> misses, next_misses;
  std::vector<internal::Revived> revived;
  // FindContacts' block pairs in the order it tests them: (distance², index into candidates).
  std::vector<std::pair<double, size_t>> order;
  int n = 0, pass = 0;
  int search = 0;  ///< FindContacts calls so far (the chunks' near_search stamps)
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

namespace internal {

/// What a face extremum e of surfaces a, b stands for when either is trimmed: itself while its
/// points lie on both materials, else the edge contact of the surface it leaves, or with both
/// trimmed the two edges' (contact/trimmed.h), with its distance and points in (a, b) order.
struct OnMaterial {
  bool on_edge = false;
  /// Where the points lie (PointParameters): with both surfaces trimmed, what the contact is
  /// tracked by; else the face extremum's parameters.
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  double beta = 0.0;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
  ExtremalStatus status = ExtremalStatus::kNotConverged;
};
OnMaterial MeasureOnMaterial(const Watched& wa, const BodyPose& pa, const Watched& wb,
                             const BodyPose& pb, const SurfaceSurfaceExtremum& e);

/// A face extremum on the material held on its surface's border (ExtremalStatus::kAtBoundary,
/// every held parameter on a trimmed surface): where a face's material reaches its surface's
/// border (an imported cylinder wall's top at a hole's rim), the border is the material's edge
/// and the held extremum its contact with the other surface, as a trim edge's is. The servo's
/// trimmed term measures it so (a face contact held on a bound, with its boundary Hessian); the
/// stage keeps and finds it alike, rather than calling it gone from the domain and finding it
/// again every pass. `on`: its MeasureOnMaterial.
bool HeldOnMaterialBorder(const Watched& wa, const Watched& wb, const SurfaceSurfaceExtremum& e,
                          const OnMaterial& on);

/// The near misses of surfaces a < b that the last pass kept (m.misses), each re-solved from its
/// parameters at poses pa, pb (a continuation solve), into m.revived: those that converged to
/// the same extremum moved (not another: FoundAnotherExtremum), one per pair of points. The
/// caller takes each as a contact, a near miss again, or neither. docs/contact.md, "Near
/// misses".
void ReviveNearMisses(GlobalContactStage::Impl& m, int a, int b, const BodyPose& pa,
                      const BodyPose& pb);

/// Whether a refinement's answer e for surfaces a, b is a near miss to keep: a converged minimum
/// with facing normals, activation ≤ β < the offsets' reach, on two untrimmed surfaces.
bool IsNearMiss(const GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                const SurfaceSurfaceExtremum& e);

}  // namespace internal

}  // namespace tangent::contact
