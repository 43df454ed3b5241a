#pragma once

#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "contact/extremal.h"
#include "contact/placed.h"
#include "nurbs/offset.h"
#include "nurbs/trim.h"

namespace tangent::contact {

/// A surface the global stage watches: on body `body` (an index into the pose snapshot), with
/// its offset mesh (both must outlive the stage).
struct GlobalSurface {
  int body = 0;
  const nurbs::NurbsSurface* surface = nullptr;
  const nurbs::OffsetMesh* mesh = nullptr;
  /// The surface's material when it is trimmed (may be null): contacts are found and kept on
  /// the material only, as face contacts there and as edge contacts (the trim edge against the
  /// other surface, contact/trimmed.h) where the face's extremal point lies off it. A contact's
  /// `u` stays the face pair's parameters (what a tracked contact is reseeded from); its β and
  /// points are the measured ones. With both surfaces of a pair trimmed, `u` is where the
  /// points lie (contact::PointParameters), and a tracked contact is re-measured in its own form
  /// from there (edge on a face, or two edges: contact::MeasureTrimmedPairAt).
  const nurbs::TrimmedDomain* trim = nullptr;
};

struct GlobalOptions {
  /// Also take a touching pair whose extremal solve ends `singular` on a continuum of minima (a
  /// rod lying in a groove: every point along the line is an extremal pair). Only where the
  /// servo holds such a pair as a line (ServoOptions::line_contacts, server/line_contacts.h):
  /// as a point it is degenerate.
  bool accept_continuum = false;
  /// A singular extremum is such a continuum only where its relative curvature is line-like,
  /// λ_min < continuum_ratio · λ_max (the servo's LineContactOptions::enter): where the servo
  /// would hold it as a line.
  double continuum_ratio = 0.1;
  /// Hold declared pairs of two untrimmed flat faces (nurbs/flat.h) by their corners
  /// (FindFaces): found and kept by the corner of either face lying over the other nearest to it
  /// (contact/face_gap.h), as the servo holds them (server/face_contacts.h).
  bool face_pairs = true;
  /// Carry near misses from pass to pass (docs/contact.md, "Near misses"): a minimum of a pair's
  /// distance apart within its offsets' reach (a refinement's answer, or a tracked contact
  /// removed as separated) is re-solved in the next pass and, a near miss or a contact again,
  /// centres a sphere of neglect as a tracked contact does: its blocks skip the narrow phase.
  /// Off: every pass finds what it finds from its seeds alone (global_bench's "cold").
  bool near_misses = true;
  /// A contact is added when its extremal distance β falls below `activation` and removed when
  /// it rises above `release` (> activation: hysteresis), leaves the domain, or is lost. The
  /// offsets of each declared pair's two meshes must reach 2 x `release` together (a face's
  /// offset may be below `release` where it was reduced below a concave radius of its own).
  double activation = 0.1e-3;
  double release = 0.2e-3;
  /// Spheres of neglect: a seed within ρ of an accepted seed or tracked contact of the same pair
  /// is neglected, unless the two are topologically far: more than `far_factor` x ρ apart along
  /// either surface (arc length through parameter space), as the paperclip's inner and outer
  /// loops are (seed 001 §5).
  double neglect_radius = 1.0e-3;
  /// Extremal pairs deeper than this (β < −max_penetration) are not contacts but the far sides
  /// of two bodies (a wire's underside against the other wire's top: a maximum of the distance
  /// like a real penetration's deepest pair, but as deep as the bodies are thick). Keep it below
  /// the thinnest body's thickness.
  double max_penetration = 0.5e-3;
  /// 4: the offsets of two touching paperclip wires overlap over ±1.3 mm along each wire, so
  /// blocks there are within 4 ρ of the contact and skipped once it is tracked (with 2, most
  /// were not and the steady pass cost 0.5 ms).
  double far_factor = 4.0;
  enum class BroadPhase { kDynamicAABBTree, kSweepAndPrune };
  BroadPhase broad_phase = BroadPhase::kDynamicAABBTree;
  int max_triangle_pairs = 100000;  ///< per chunk pair (FCL's num_max_contacts)
  /// Each offset mesh is cut into blocks of grid cells (this many along u and v), each its own
  /// OBBRSS tree: FCL's narrow phase runs only on blocks whose boxes overlap (measured on two
  /// hooked paperclips: one 6000-triangle tree against another, 213 µs per collide), and a block
  /// pair lying, on both surfaces, within far_factor x ρ along the surface of a tracked contact
  /// is skipped: any contact it holds is that contact (the events count it as known). Small
  /// blocks make the skip effective; build the offset meshes with a max_edge (MakeOffsetMesh)
  /// well below far_factor x ρ so that flat stretches are cut too.
  int chunk_u_cells = 1, chunk_v_cells = 7;
  /// A surface pair with more near block pairs than this (its blocks near the other surface's
  /// box, one count times the other) pairs them by a sweep along one axis; fewer, every one
  /// against every other. Measured: twenty clips' ~10 x 10 ran 13 % slower through the sweep's
  /// sorts; a ball in a socket's ~1,800 x 960 made its test 4.3 s instead of 3.3 s without it.
  int sweep_above = 4096;
};

/// An extremal contact between surfaces a < b (indices into the stage's surfaces): parameters
/// (u, v) on a and (s, t) on b, signed distance β (< 0 interpenetrating), world points.
struct GlobalContact {
  int a = -1, b = -1;
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  double beta = 0.0;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
};

struct ContactEvent {
  enum class Kind { kAdded, kRemoved };
  /// kSplit: a tracked contact that became a saddle of the distance (the surfaces cross near
  /// it; relative_curvature.h) is removed and the minima on either side are added, all with
  /// this reason. kMerged: two tracked contacts of a pair re-solved to one point (the minima of a
  /// split came back together): the later one is removed.
  enum class Reason { kApproached, kSeparated, kLeftDomain, kLost, kSplit, kMerged };
  Kind kind = Kind::kAdded;
  Reason reason = Reason::kApproached;
  GlobalContact contact;
};
const char* ToString(ContactEvent::Reason r);

struct GlobalStats {
  int candidate_pairs = 0;      ///< surface pairs the broad phase reported (after the filter)
  int chunk_pairs_tested = 0;   ///< mesh strips whose boxes overlap, narrow phase run
  int chunk_pairs_skipped = 0;  ///< ... skipped: near a tracked contact or near miss on both
  int near_misses = 0;          ///< near misses carried from the last pass, re-solved and kept
  int triangle_pairs = 0;       ///< intersecting offset-triangle pairs (narrow phase)
  int seeds_neglected = 0;      ///< inside a sphere of neglect
  int seeds_refined = 0;        ///< Newton solves run
  int found = 0;                ///< distinct extremal contacts with β < activation
};

/// The global contact stage (seed 001 §5, Fig. 3 and 5; design.md §2): a polygonal collision
/// test on offset meshes (FCL: an OBBRSS tree per surface, a broad-phase manager across them)
/// seeds the extremal-distance Newton solver; spheres of neglect drop seeds that would find a
/// contact already known; hysteresis turns distances into add/remove events. Only surface pairs
/// the scene declares (one by one, or as the faces of two bodies) are ever tested. A pass reads a
/// pose snapshot and the tracked contacts and writes events: the stage shares no mutable state with
/// its caller, so it can run on its own thread. (It allocates: it is not the servo loop.) From one
/// pass to the next it keeps only its near misses (GlobalOptions::near_misses).
class GlobalContactStage {
 public:
  GlobalContactStage(std::vector<GlobalSurface> surfaces,
                     const std::vector<std::pair<int, int>>& pairs, const GlobalOptions& options);
  /// With body pairs as well (a scene's "these two parts may touch", docs/cad.md): every
  /// surface of body a against every surface of body b is tested (the surfaces of both need
  /// offset meshes). The declarations are kept as they are given: memory grows with the
  /// surfaces and the declarations, never with the pairs of surfaces they cover.
  GlobalContactStage(std::vector<GlobalSurface> surfaces,
                     const std::vector<std::pair<int, int>>& pairs,
                     const std::vector<std::pair<int, int>>& body_pairs,
                     const GlobalOptions& options);
  ~GlobalContactStage();
  GlobalContactStage(const GlobalContactStage&) = delete;
  GlobalContactStage& operator=(const GlobalContactStage&) = delete;

  /// One pass. `poses`: world poses of all bodies (indexed by GlobalSurface::body).
  void Run(const std::vector<BodyPose>& poses, const std::vector<GlobalContact>& tracked,
           std::vector<ContactEvent>* events, GlobalStats* stats = nullptr);
  /// The contacts with β < activation found by the last pass (sorted by pair, then u).
  const std::vector<GlobalContact>& found() const { return found_; }
  /// The surface pairs whose offsets crossed in the last pass, each with the smallest distance
  /// its refinements measured on the material (+∞ when none converged to a minimum): the
  /// clearance certificate's view of pairs nearer than their offsets (contact/clearance.h).
  struct Viewed {
    int a = -1, b = -1;
    double nearest = 0.0;
  };
  const std::vector<Viewed>& viewed() const { return viewed_; }
  const GlobalOptions& options() const { return options_; }

  struct Impl;  ///< FCL objects and per-surface data (opaque)

 private:
  // The pass's steps (global.cc), in order.
  /// 1. Broad phase: surface pairs whose boxes overlap, then their overlapping block pairs.
  void BroadPhase(const std::vector<BodyPose>& poses, GlobalStats* st);
  /// 2–4 for one surface pair (global_seeds.cc): its tracked contacts and the near misses the
  /// last pass kept (re-solved) centre spheres of neglect; its block pairs, nearest first and
  /// each unless near a centre, through the narrow phase (offset triangles); their seeds
  /// clustered outside the spheres, each new cluster refined at once into a contact (found_) or
  /// a near miss, either of which centres a sphere too.
  void FindContacts(int a, int b, size_t first, size_t last, const std::vector<BodyPose>& poses,
                    const std::vector<GlobalContact>& tracked, GlobalStats* st);
  /// 4b. Nested pairs: the surface pairs the broad phase reported whose offsets did not cross,
  /// with nothing tracked, and whose boxes mostly share their space (a ball in a socket, a rod
  /// along a groove: offsets that contain one another never cross), solved from their samples
  /// (contact/global_minima.h).
  void FindNested(const std::vector<BodyPose>& poses, const std::vector<GlobalContact>& tracked,
                  GlobalStats* st);
  /// 4c. Face pairs: declared pairs of two flat faces (nurbs/flat.h) the broad phase reported,
  /// with nothing tracked: the corner of either lying over the other nearest to it
  /// (contact/face_gap.h). (Their offsets are parallel sheets that never cross, and their
  /// extremal pair is a continuum or a domain corner: the narrow phase does not see them.)
  void FindFaces(const std::vector<BodyPose>& poses, const std::vector<GlobalContact>& tracked,
                 GlobalStats* st);
  /// 5. Events with hysteresis: tracked contacts re-solved (removals; a saddle split into the
  /// minima beside it, two at one point merged), found ones added.
  void Events(const std::vector<BodyPose>& poses, const std::vector<GlobalContact>& tracked,
              std::vector<ContactEvent>* events);

  std::unique_ptr<Impl> impl_;
  GlobalOptions options_;
  std::vector<GlobalContact> found_;
  std::vector<Viewed> viewed_;
  std::vector<GlobalContact> split_;  ///< minima beside tracked saddles (Events' workspace)
  std::vector<char> removed_;         ///< per tracked contact, removed this pass
};

}  // namespace tangent::contact
