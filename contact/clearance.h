#pragma once

// Certified clearance between the parts the global stage watches (issue 33, "no tunnelling";
// docs/stability.md "No tunnelling"): for each pair of bodies that may touch, a lower bound on
// the distance between their watched surfaces at one set of poses, from the surfaces' certified
// tessellations. The servo keeps every step's motion within it (optimizer/clearance_guard.h),
// so a pair that is apart cannot pass through itself between two passes of the stage, however
// late the next pass comes.

#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "contact/global.h"
#include "contact/placed.h"

namespace tangent::contact {

/// A sphere that holds every point of a watched surface, in its body's frame: the centre of its
/// tessellation's box, and the farthest vertex plus the tessellation's certified bound (every
/// surface point lies within that bound of a triangle, and every triangle within the vertices'
/// ball).
struct BoundingSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;
};
BoundingSphere SurfaceSphere(const nurbs::OffsetMesh& mesh);

/// The farthest a point of the surface lies from its body's origin (m), by the same argument.
double SurfaceReach(const nurbs::OffsetMesh& mesh);

/// The body pairs the stage watches (each a < b, sorted, no repeats): the bodies of the declared
/// surface pairs whose surfaces both have offset meshes, and the declared body pairs.
std::vector<std::pair<int, int>> WatchedBodyPairs(
    const std::vector<GlobalSurface>& surfaces, const std::vector<std::pair<int, int>>& pairs,
    const std::vector<std::pair<int, int>>& body_pairs);

/// Per watched body pair, a lower bound on the distance between the two bodies' watched
/// surfaces, the least over their surface pairs of:
///  - for a pair whose offsets did not cross in the stage's pass, a certified bound: the gap
///    between the surfaces' bounding spheres when that is at least `exact_within` (5 mm: a
///    part moves about 1 mm between two passes at the hand's 1 m/s), else the
///    distance between their tessellations (FCL, exact triangle distances) less both
///    tessellations' certified bounds (every surface point lies within its bound of its mesh);
///  - for a pair whose offsets crossed (in the stage's view), the smallest distance the pass's
///    refinements measured on the material (GlobalContactStage::viewed; none converged to a
///    minimum: not certified), capped by what the
///    offsets say of the rest, r_a + r_b − 2(ε_a + ε_b) (r the offsets, ε the tessellations'
///    bounds). This is as exact as the stage's own contact detection, which rests on the same
///    refinements; a tessellation's bound alone would hold a trimmed face's uncut cells (which
///    reach past its trim) off the other part for ever.
/// Surface pairs in contact (tracked by the servo, or found by the stage's pass) are the contact
/// rows' to hold and are left out. The value reported is the bound less a `standoff` (half the
/// stage's activation distance): the guard then holds a pair at least that far apart, near
/// enough that the stage's next pass takes it as a contact. Pairs not certified beyond twice the
/// standoff are left out too: nearer, a facing pair is the stage's next contact, and a pair the
/// stage does not take as a contact (a face's back, a ball on a face beside the wall that shares
/// its rim) would otherwise be held still for ever. A body pair with none left: +∞.
class ClearanceCertifier {
 public:
  ClearanceCertifier(std::vector<GlobalSurface> surfaces,
                     const std::vector<std::pair<int, int>>& pairs,
                     const std::vector<std::pair<int, int>>& body_pairs, double standoff,
                     double exact_within = 0.005);
  ~ClearanceCertifier();
  ClearanceCertifier(const ClearanceCertifier&) = delete;
  ClearanceCertifier& operator=(const ClearanceCertifier&) = delete;

  const std::vector<std::pair<int, int>>& body_pairs() const { return body_pairs_; }
  /// Builds every watched surface's tessellation tree now instead of on its first use (each is
  /// megabytes: a server builds them before it serves, so that none is allocated mid-run on the
  /// global thread and its resident set is flat from the start). @return how many were built.
  int BuildAll();

  /// One certificate at `poses` (indexed by GlobalSurface::body). `in_contact`: surface pairs
  /// (a < b) left out; `viewed`: the stage's pass's (empty: every pair by its tessellations).
  /// Writes one value per body_pairs() entry (m; +∞ not certified).
  void Certify(const std::vector<BodyPose>& poses,
               const std::vector<std::pair<int, int>>& in_contact,
               const std::vector<GlobalContactStage::Viewed>& viewed,
               std::vector<double>* clearance);
  /// The certificate of a stage's last pass, at the `poses` it ran on: the surface pairs of
  /// `tracked` (the servo's contacts) and of the pass's found() left out, its viewed() taken.
  void Certify(const std::vector<BodyPose>& poses, const std::vector<GlobalContact>& tracked,
               const GlobalContactStage& stage, std::vector<double>* clearance);

  /// Lower bound on the distance between surfaces a and b at `poses`, m (the step above for one
  /// surface pair; may be ≤ 0).
  double SurfaceClearance(int a, int b, const std::vector<BodyPose>& poses);
  /// The gap between surfaces a's and b's bounding spheres at `poses` (m; may be negative).
  double SphereGap(int a, int b, const std::vector<BodyPose>& poses) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  std::vector<std::pair<int, int>> body_pairs_;
  std::vector<std::pair<int, int>> in_contact_;  ///< Certify's workspace
};

}  // namespace tangent::contact
