#pragma once

// Contacts on trimmed surfaces (docs/trimming.md, "Contacts at trims"): the distance between a
// trimmed surface f and a surface g measured on f's material only. Where the extremal point of
// the pair (f, g) lies on f's material it is the face contact's; where it lies off the material
// the contact is an edge contact: the trim edge E(τ) = f(c(τ)) nearest that point against g, at
// their curve–surface extremum (seed 001 Eqs. 22–24). The optimizer's TrimmedContactTerm and the
// global stage both measure through here, so the servo and the stage agree on what is touching.

#include <vector>

#include <Eigen/Core>

#include "contact/edge_edge.h"
#include "contact/extremal.h"
#include "contact/placed.h"
#include "nurbs/curve.h"
#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::contact {

/// A trimmed surface's edges, ready for curve–surface solves: each loop's curves cut where they
/// are only C⁰ (a polyline's vertices; not a rational circle's full knots, where it is C¹) into
/// smooth pieces, in order round the loop, over the curves' own parameters. A loop that is one
/// smooth piece closing on itself with one derivative (a circle) is periodic: its parameter wraps.
/// The edge's extremal Newton runs on one smooth piece; when its extremum stops at a piece's end it
/// walks on to the neighbour, and it stays at a corner only where both neighbours put it there.
class TrimEdges {
 public:
  struct Piece {
    int curve = 0;  ///< the loop's curve this piece is cut from
    nurbs::NurbsCurve2d c;
    bool periodic = false;  ///< closed on itself, C¹ across its ends
  };
  /// An edge extremum being followed: which piece, and (s, t, τ) (g's parameters, then the
  /// piece's curve parameter).
  struct Edge {
    int loop = -1, piece = -1, curve = -1;
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    CurveSurfaceExtremum ext;
  };

  /// f and its trim must outlive this.
  TrimEdges(const nurbs::NurbsSurface* f, const nurbs::TrimmedDomain* trim);

  const nurbs::NurbsSurface& surface() const { return *f_; }
  const nurbs::TrimmedDomain& trim() const { return *trim_; }
  const std::vector<std::vector<Piece>>& loops() const { return pieces_; }

  /// The piece of loop near.loop holding the loop point `near`.
  int PieceOf(const nurbs::TrimmedDomain::Closest& near) const;
  /// Places *e on the piece holding `near` (TrimmedDomain::Nearest's closest point), g's
  /// parameters `st`.
  void Start(const nurbs::TrimmedDomain::Closest& near, const Eigen::Vector2d& st, Edge* e) const;
  /// Same, with g's parameters those of g's point nearest the edge point (a point–surface solve
  /// from `st`): the face pair's own point on g can lie far round g from where g meets the edge
  /// (a ball over a hole: its lowest point against the rim's). Allocation free.
  void StartNear(const nurbs::TrimmedDomain::Closest& near, const nurbs::NurbsSurface& g,
                 const BodyPose& pose_g, const BodyPose& pose_f, const Eigen::Vector2d& st,
                 Edge* e) const;
  /// The edge's extremum against g (on body pose_g; f on pose_f) from *e, walking along the
  /// loop while it stops at a piece's end (at most once round). Allocation free.
  void Solve(const nurbs::NurbsSurface& g, const BodyPose& pose_g, const BodyPose& pose_f,
             Edge* e) const;
  /// Piece `piece` of loop `loop` as a curve on f's body.
  BodyCurve Curve(int loop, int piece) const {
    const Piece& p = pieces_[static_cast<size_t>(loop)][static_cast<size_t>(piece)];
    return BodyCurve(f_, &p.c, p.periodic);
  }
  /// The piece *e is on as a curve on f's body.
  BodyCurve Curve(const Edge& e) const { return Curve(e.loop, e.piece); }

 private:
  const nurbs::NurbsSurface* f_;
  const nurbs::TrimmedDomain* trim_;
  std::vector<std::vector<Piece>> pieces_;
};

/// An edge–edge contact followed (docs/trimming.md, "Edge against edge"): a piece of f's loops
/// and one of g's, (τ_f, τ_g), and ν, the direction β is measured along (the common normal
/// σ(a' × b')/|a' × b'| from g's edge towards f's; ±d/|d| where the extremum is held at a joint
/// of a loop or the edges are parallel). β = (a − b)·ν.
struct EdgeEdgeFollow {
  int loop_f = -1, piece_f = -1, loop_g = -1, piece_g = -1;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  Eigen::Vector3d nu = Eigen::Vector3d::Zero();
  CurveCurveExtremum ext;
  CurveCurveEval eval;         ///< the two edges evaluated at the extremum
  bool common_normal = false;  ///< ν is the common normal (both parameters free, not parallel)
};
/// Solves *e from its pieces and x, walking along either loop while the extremum stops at a
/// piece's end (at most once round each), and measures it: ν keeps the side of `side` (the last
/// ν, or the form's it switched from). Allocation free.
void SolveEdgeEdge(const TrimEdges& edges_f, const BodyPose& pose_f, const TrimEdges& edges_g,
                   const BodyPose& pose_g, const Eigen::Vector3d& side, EdgeEdgeFollow* e);

/// The distance between trimmed f and g on f's material, for a face extremum `face` of the pair
/// (f, g) (its u: (u, v) on f, (s, t) on g): on the material, the face's; off it (or held on
/// f's untrimmed border off the material), the nearest edge's against g. β > 0 apart. The edge
/// is followed from `from` (an earlier measure's edge) when that is on the loop nearest the face
/// point, else started there (TrimEdges::StartNear). Allocation free.
struct TrimmedMeasure {
  bool on_edge = false;
  TrimmedForm form = TrimmedForm::kFace;
  TrimEdges::Edge edge;  ///< when on_edge: f's edge (kEdgeOfF) or g's (kEdgeOfG) against the face
  /// Measured without the faces' extremum (MeasureTrimmedPair's `face` null), an edge against a
  /// face whose multiplier says the face offers a nearer point: solve the faces from here.
  bool face_wanted = false;
  EdgeEdgeFollow edge_edge;  ///< when kEdgeEdge
  double beta = 0.0;
  Eigen::Vector3d p_f = Eigen::Vector3d::Zero(), p_g = Eigen::Vector3d::Zero();
  ExtremalStatus status = ExtremalStatus::kNotConverged;
};
/// The last face point a measure found on the material, and how far (parameter units) it may
/// move with that answer (nurbs::TrimmedDomain::Contains' clearance). Per-solve data: the
/// evaluations of a tracked contact move it by far less, and skip the classification.
struct MaterialMemo {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  double clearance = 0.0;  ///< 0: nothing remembered
};
/// `memo` (may be null): read and updated; the answer is the same with or without it.
TrimmedMeasure MeasureTrimmed(const TrimEdges& edges, const BodyPose& pose_f,
                              const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                              const SurfaceSurfaceExtremum& face,
                              const TrimEdges::Edge* from = nullptr, MaterialMemo* memo = nullptr);

/// The distance between trimmed f and g measured on both faces' materials (g may be untrimmed:
/// edges_g null, and then this is MeasureTrimmed), for a face extremum `face` of (f, g) (null
/// only with both trimmed and `from` an edge form: then an edge against a face whose own
/// multiplier turns negative reports face_wanted, and the caller solves the faces), as a
/// local problem: min |a − b| over both materials near the contact `from` (the last measure; may
/// be null). The face's extremum where its points lie on both materials; else the contact in
/// the form it had, followed: an edge against the other face while its point there lies on that
/// face's material, else the two edges; two edges while each edge constraint's multiplier is
/// non-negative (neither face offers a nearer point), else the edge against the face that does.
/// From a face (or nothing), the edge of the face the extremum left first, started at the loop
/// point nearest it. Every switch is continuous in β: where an edge's point crosses the other
/// face's edge it is the edges' extremum too (d ⟂ both edges), with the same β, and a multiplier
/// changes sign where the two forms' extrema meet. Allocation free.
TrimmedMeasure MeasureTrimmedPair(const TrimEdges& edges_f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const TrimEdges* edges_g,
                                  const BodyPose& pose_g, const SurfaceSurfaceExtremum* face,
                                  const TrimmedMeasure* from, MaterialMemo* memo_f,
                                  MaterialMemo* memo_g);

/// Where a contact between two trimmed faces has its points on the faces: (u, v) of p_f on f and
/// (s, t) of p_g on g. A face contact's are its own parameters (`face_u`); an edge point's are
/// its loop's point in the domain. The servo reports, and the global stage tracks, such a
/// contact by these: the faces' extremum can lie anywhere off both materials, and two edge
/// contacts of one face pair (an edge crossing a rim twice) share it.
Eigen::Vector4d PointParameters(const TrimEdges& edges_f, const TrimEdges& edges_g,
                                const TrimmedMeasure& m, const Eigen::Vector4d& face_u);
/// The contact whose points lie at `u` (PointParameters), measured in its own form: a point on
/// its face's loop (within 1e-9 of the domain) is an edge point, seeded there. False (nothing
/// measured) when neither point lies on its loop: a face contact, which the caller solves.
/// Allocation free.
bool MeasureTrimmedPairAt(const TrimEdges& edges_f, const BodyPose& pose_f,
                          const TrimEdges& edges_g, const BodyPose& pose_g,
                          const Eigen::Vector4d& u, TrimmedMeasure* m);

}  // namespace tangent::contact
