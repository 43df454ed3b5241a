#pragma once

// The trimming constraints of seed 001 §3.4 (docs/trimming.md): a contact between a trimmed
// surface f on body a and a surface g on body b stays on f's material, or on its edge.
//
// Two extremal problems are tracked: the contact's, the pair (u_e, s_e) of f and g
// (contact::SolveSurfaceSurface), and the trim edge's, the point of the edge curve
// E(τ) = f(c(τ)) (c a curve of a trimming loop in f's domain) nearest g, (τ*, s_c)
// (contact::SolveCurveSurface through the curve–surface relations, seed 001 Eqs. 22–24). With
// the material on the left of c (trim.h) and the edge point c* = c(τ*):
//   kParametric    r = ν(τ*)·(u_e − c*),               ν = J c'/|c'| the domain normal into the
//                                                      material (J a quarter turn),
//   kSameSurface   r = m(τ*)·(f(u_e) − f(c*)),          m = n × E'/|E'| the edge's in-surface
//                                                      normal into the material (f's frame),
//   kOtherSurface  r = m_W(τ*)·(g(s_e) − f(c*)),        g's contact point against the edge point
//                                                      (world),
// as an inequality r ≥ 0 (the contact keeps to the material) or an equality r = 0 (the contact
// on the edge). The seed writes the norms |u_e − c*| etc.; the projections on the edge's normal
// are their signed, differentiable forms (equal where the contact sits on the edge's normal).
//
// Exact Jacobians through both extremal Jacobians (u_e,q: contact::ContactJacobianImplicit;
// τ_q: contact::CurveSurfaceJacobianImplicit). Since ν ⟂ c' and m ⟂ E', the edge point's own
// motion drops out and only the normal's turning with τ remains:
//   kParametric    r_q = ν·u_e,q + ((u_e − c*)·ν') τ_q
//   kSameSurface   r_q = m·(f_u u_e,q + f_v v_e,q) + ((f(u_e) − E)·m') τ_q        (f's frame)
//   kOtherSurface  r_q = m_W·(g_q|_s + g_s s_q + g_t t_q − E_q|_τ) + Δ·(∂(R_a m)/∂q_a + R_a m' τ_q)
// with ν' = J(c''/|c'| − c'(c'·c'')/|c'|³), m' = n' × T + n × T', n' the unit normal's change
// along the edge and T' = (I − TTᵀ)E''/|E'|. No second derivatives (Gauss–Newton).

#include <memory>

#include "contact/extremal.h"
#include "contact/placed.h"
#include "contact/trimmed.h"
#include "nurbs/curve.h"
#include "nurbs/surface.h"
#include "nurbs/trim.h"
#include "optimizer/contacts.h"
#include "optimizer/term.h"

namespace tangent::optimizer {

enum class TrimForm { kParametric, kSameSurface, kOtherSurface };
const char* ToString(TrimForm form);

class TrimConstraintTerm final : public Term {
 public:
  struct State final : TermState {
    Eigen::Vector4d pair;  ///< the contact's tracked (u, v, s, t)
    Eigen::Vector3d edge;  ///< the edge's tracked (s, t, τ): g's parameters, then the curve's
    Vector7d q_a, q_b;
    bool valid = false;
    /// The line search's base point (TermState::Anchor): the pair's, and the edge's here.
    FollowAnchor<Eigen::Vector4d> anchor;
    Eigen::Vector3d edge_anchor[kAnchorSlots] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    void Anchor(int slot) override {
      anchor.Keep(slot, pair, q_a, q_b, valid);
      edge_anchor[slot] = edge;
    }
    void Rewind(int slot) override {
      anchor.Restore(slot, &pair, &q_a, &q_b, &valid);
      edge = edge_anchor[slot];
    }
    contact::SurfaceSurfaceExtremum pair_ext;
    contact::SurfacePairEval pair_eval;
    contact::CurveSurfaceExtremum edge_ext;
    contact::CurveSurfaceEval edge_eval;
  };
  /// f (on body a) carries the trim curve `curve` (in f's domain, material on its left); the
  /// surfaces and the curve must outlive the term. Seeds: the pair's (u, v, s, t) and the edge's
  /// (s, t, τ).
  TrimConstraintTerm(TrimForm form, int body_a, const nurbs::NurbsSurface* f,
                     const nurbs::NurbsCurve2d* curve, int body_b, const nurbs::NurbsSurface* g,
                     const Eigen::Vector4d& pair_seed, const Eigen::Vector3d& edge_seed);

  std::string name() const override;
  int dim() const override { return 1; }
  int body_a() const override { return body_a_; }
  int body_b() const override { return body_b_; }
  std::unique_ptr<TermState> MakeState() const override;
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;

 private:
  void Update(const std::vector<BodyPose>& poses, State* st) const;

  TrimForm form_;
  int body_a_, body_b_;
  const nurbs::NurbsSurface* f_;
  const nurbs::NurbsCurve2d* curve_;
  const nurbs::NurbsSurface* g_;
  contact::BodyCurve edge_;
  Eigen::Vector4d pair_seed_;
  Eigen::Vector3d edge_seed_;
};

/// The signed distance β between a trimmed surface f (body a) and a surface g (body b) that
/// measures only f's material (docs/trimming.md, "Contacts at trims"), one row; as an inequality
/// β ≥ 0 it is non-penetration against the part that exists. While the contact's extremal point
/// u_e on f lies on the material, β is the face contact's, measured, tracked and differentiated
/// (with its Hessian) by a SurfaceContactTerm. When u_e leaves the material the contact becomes
/// an edge contact: β is the signed distance between the trim edge E(τ) = f(c(τ)) nearest u_e
/// (contact::MeasureTrimmed) and g, at their curve–surface extremum, (E − G)·n_g. The switch is
/// continuous: where u_e crosses the edge, the face's extremal point is on the edge and is the
/// edge's extremum too (d ⟂ f's tangent plane, so d·E' = 0), so both forms give the same β
/// there. Either way
///   ∇β = n·(∂p_a/∂q − ∂p_b/∂q) at fixed parameters
/// (the free parameters are stationary), n the direction the extremum measures β along. The
/// Hessian: the face contact's on the face; on the edge the same formula with the curve in
/// place of f (trims.cc), and the solver's Gauss–Newton model where the edge's extremum is held
/// on a bound.
class TrimmedContactTerm final : public Term {
 public:
  struct State final : ContactSlotState {
    std::unique_ptr<TermState> face_state;  ///< the face contact's (a SurfaceContactTerm's)
    contact::TrimmedMeasure measure;        ///< the last measure: its form, the edge followed
    bool on_edge = false;                   ///< the last evaluation measured an edge
    int64_t switches = 0;                   ///< changes of form (face, either edge, edge–edge)
    contact::MaterialMemo material, material_g;  ///< the last face points found on each material
    Vector7d q_a, q_b;
    bool valid = false;
    contact::CurveSurfaceEval edge_eval;  ///< an edge against a face (two edges': measure's)
    Eigen::Vector3d row_direction = Eigen::Vector3d::Zero();  ///< the curve row's own n
    /// The contact as reported: the face pair's parameters (with both faces trimmed, where its
    /// points lie: contact::PointParameters), and β, points and direction of what is measured
    /// (the edge's while on_edge).
    contact::SurfaceSurfaceExtremum reported;
    SurfaceContactTerm::State& face() const {
      return static_cast<SurfaceContactTerm::State&>(*face_state);
    }
    /// The line search's base point (TermState::Anchor): the measure followed and the face
    /// contact's (the material memos give the same answer either way).
    FollowAnchor<contact::TrimmedMeasure> anchor;  ///< with the measure followed
    bool seeded_anchor[kAnchorSlots] = {false, false};
    void Anchor(int slot) override {
      face_state->Anchor(slot);
      anchor.Keep(slot, measure, q_a, q_b, valid);
      seeded_anchor[slot] = seeded;
    }
    void Rewind(int slot) override {
      face_state->Rewind(slot);
      anchor.Restore(slot, &measure, &q_a, &q_b, &valid);
      seeded = seeded_anchor[slot];
    }
    const contact::SurfaceSurfaceExtremum& extremum() const override { return reported; }
    void Reseed(const Eigen::Vector4d& u_new) override {
      face().Reseed(u_new);
      reported.u = u_new;
      valid = false;
      seeded = true;
    }
    /// Reseeded: with both faces trimmed, the contact is first measured in the form its points
    /// (reported.u, contact::PointParameters) say.
    bool seeded = false;
    /// The state of a term on another face pair (a BodyContactTerm's slot moved): the face
    /// contact rebound, no edge followed, nothing remembered of the material. Reseed next.
    /// Allocation free.
    void Rebind(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g) {
      face().Rebind(f, g);
      valid = false;
      on_edge = false;
      seeded = false;
      measure.form = contact::TrimmedForm::kFace;
      material = {};
      material_g = {};
    }
  };
  /// The surfaces and the trims must outlive the term. `trim_g`: g's trim when g is trimmed too
  /// (null: g's whole surface is material); then the contact takes all four forms
  /// (contact::MeasureTrimmedPair): on the faces, f's edge against g, g's edge against f, and
  /// edge against edge, β = (a − b)·ν along the edges' common normal (contact/edge_edge.h).
  TrimmedContactTerm(int body_a, const nurbs::NurbsSurface* f, const nurbs::TrimmedDomain* trim,
                     int body_b, const nurbs::NurbsSurface* g, const Eigen::Vector4d& seed,
                     const ContactTracking& tracking = {},
                     const nurbs::TrimmedDomain* trim_g = nullptr);
  /// The same with the edges built already (`edges` on f and its trim, `edges_g` on g and its
  /// trim or null): shared by the terms of one face, and allocation free (a BodyContactTerm's
  /// slot moving between face pairs).
  TrimmedContactTerm(int body_a, std::shared_ptr<const contact::TrimEdges> edges, int body_b,
                     const nurbs::NurbsSurface* g, const Eigen::Vector4d& seed,
                     const ContactTracking& tracking = {},
                     std::shared_ptr<const contact::TrimEdges> edges_g = nullptr);

  std::string name() const override { return "trimmed_contact"; }
  int dim() const override { return 1; }
  int body_a() const override { return body_a_; }
  int body_b() const override { return body_b_; }
  std::unique_ptr<TermState> MakeState() const override;
  bool Idle(const TermState* state) const override {
    return !static_cast<const State*>(state)->active;
  }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;
  /// The face contact's reach on the face, the edge row's on the edge.
  bool Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const override;

 private:
  void Update(const std::vector<BodyPose>& poses, State* st) const;

  int body_a_, body_b_;
  const nurbs::NurbsSurface* g_;
  SurfaceContactTerm face_;
  std::shared_ptr<const contact::TrimEdges> edges_, edges_g_;
};

std::shared_ptr<TrimConstraintTerm> MakeTrimConstraint(TrimForm form, int body_a,
                                                       const nurbs::NurbsSurface* f,
                                                       const nurbs::NurbsCurve2d* curve, int body_b,
                                                       const nurbs::NurbsSurface* g,
                                                       const Eigen::Vector4d& pair_seed,
                                                       const Eigen::Vector3d& edge_seed);

}  // namespace tangent::optimizer
