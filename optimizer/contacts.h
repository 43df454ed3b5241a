#pragma once

#include <memory>

#include "contact/extremal.h"
#include "contact/tracker.h"
#include "optimizer/joints.h"
#include "optimizer/term.h"

namespace tangent::optimizer {

/// What the server needs of a contact slot's per-solve data, whichever term measures the
/// contact (SurfaceContactTerm, TrimmedContactTerm): whether the slot is in use, the contact as
/// it stands, and a way to restart it.
///
/// Contact slots are the server's way of adding and dropping contacts without changing the
/// problem's structure: an inactive term evaluates nothing and reports β = kInactiveDistance
/// with zero derivatives, which as an inequality (β ≥ 0) is inactive and gets multiplier 0. Not
/// for equalities.
struct ContactSlotState : TermState {
  static constexpr double kInactiveDistance = 1.0;  // m
  bool active = true;
  int64_t tracked_steps = 0;  ///< evaluations answered by the tracker
  int64_t solves = 0;         ///< evaluations that needed a full solve
  int64_t lost = 0;           ///< tracker steps that reported `lost` (then solved)
  /// Solves that found another extremum (contact::FoundAnotherExtremum): the pair is then held
  /// at its last parameters (β = d·n there, continuous in the poses) until the global stage
  /// re-finds the contact.
  int64_t jumps = 0;
  /// Solves that ended not converged or on a singular Newton matrix: the pair is then held at
  /// the parameters the solve started from, and the tracker goes on from there.
  int64_t undecided = 0;
  /// Which form the contact took at the last evaluation (contact::TrimmedForm): kFace but on
  /// trimmed pairs, where an edge against a face, or two edges, may hold it.
  contact::TrimmedForm form = contact::TrimmedForm::kFace;
  /// The contact at the last evaluated poses: the face pair's parameters (u, v, s, t) (what
  /// Reseed takes), the distance β it is held to and the two points it is measured between.
  virtual const contact::SurfaceSurfaceExtremum& extremum() const = 0;
  /// Restarts tracking from new parameters (after a global contact search).
  virtual void Reseed(const Eigen::Vector4d& u_new) = 0;
  /// A global-stage contact event: the slot takes the contact at parameters u.
  void Activate(const Eigen::Vector4d& u_new) {
    active = true;
    Reseed(u_new);
  }
  void Deactivate() { active = false; }
};

/// A free slot's row (ContactSlotState): β = kInactiveDistance, no gradient.
inline void InactiveRow(Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                        Eigen::Ref<Eigen::MatrixXd> J_b) {
  r[0] = ContactSlotState::kInactiveDistance;
  J_a.setZero();
  J_b.setZero();
}

/// How a contact term follows its pair between solves: the tracker's corrector steps and when
/// its point is taken as the contact. The defaults are exact: the point is the extremum to the
/// extremal solver's own tolerance, else a full solve runs. docs/benchmarks.md measures what
/// other settings cost and gain.
struct ContactTracking {
  int corrector_steps = 1;  ///< contact::TrackerOptions::corrector_steps (0–3)
  /// The tracker's point is the contact when the contact equations' scaled residual there is
  /// below this (contact::ExtremumAt); else a full extremal solve runs. At 1e-12 one Newton step
  /// from it would move it by ~1e-24. A larger value keeps the tracker's point as it stands: β
  /// is then d·n at a point that is not quite extremal, an error second order in the residual.
  double accept_residual = 1e-12;
};

/// The signed distance β between a surface f on body a and a surface g on body b at their
/// extremal pair (seed 001 §3.3, design.md §4.1–4.2), one row: as an equality it is the
/// "floating contact" β = 0 (the surfaces touch and may roll and slide), as an inequality
/// non-penetration β ≥ 0.
///
/// The pair's parameters (u, v, s, t) are tracked in the term's State: each evaluation at new poses
/// runs the extremal Newton solver from the last parameters (contact::SolveSurfaceSurface,
/// allocation free), so the parameters follow the motion and β is exact to the solver's
/// tolerance. Derivatives (docs/optimizer.md "Contact terms"):
///   ∇β = n_gᵀ (∂f/∂q − ∂g/∂q)|_u            (the u-terms vanish at an extremum),
///   ∇²β = Pᵀ n_q + n·∂²(f − g)/∂q²|_u + V_fᵀ u_q^f − V_gᵀ u_q^g,
/// with P = ∂(f − g)/∂q|_u, n_q the total derivative of the unit normal of g (its rotation and
/// its change with (s, t)), V the normal component of ∂P/∂u and u_q the closed-form contact
/// Jacobian (contact::ContactJacobianClosedForm). Where u_q is singular the u-terms are dropped
/// (Gauss–Newton in those directions).
///
/// The tracked parameters, the last extremum and evaluation, and whether the slot is active are
/// per-solve data (State, in the solver's ProblemData); the term itself is immutable.
class SurfaceContactTerm final : public Term {
 public:
  struct State final : ContactSlotState {
    State(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
          const contact::TrackerOptions& options)
        : tracker(f, g, options) {}
    Eigen::Vector4d u;  ///< tracked (u, v, s, t)
    /// contact/'s tracker follows the pair between solves (predict with u_q, one correction);
    /// a full extremal solve from the last parameters runs when it is not tracking (start,
    /// reseed), when it reports anything but `tracked`, or when its corrected point is not an
    /// extremum to the tolerance, and restarts it.
    contact::ContactTracker tracker;
    bool tracking = false;
    contact::TrackStatus track_status = contact::TrackStatus::kLost;  ///< the last step's
    Vector7d q_f, q_g;  ///< poses of the last evaluation
    bool valid = false;
    /// The line search's base point (TermState::Anchor): the next evaluation after Rewind
    /// solves afresh from its parameters, with the jump and undecided rules against them.
    FollowAnchor<Eigen::Vector4d> anchor;
    void Anchor(int slot) override { anchor.Keep(slot, u, q_f, q_g, valid); }
    void Rewind(int slot) override {
      anchor.Restore(slot, &u, &q_f, &q_g, &valid);
      tracking = false;
    }
    contact::SurfaceSurfaceExtremum ext;
    contact::SurfacePairEval eval;
    /// Rows stay on their minimum (docs/contact.md, "Rows that stay on their minimum"): with
    /// this set, an evaluation that ends on a saddle of the distance (past a pitchfork, Newton
    /// from the predicted point may converge to the nearest stationary point:
    /// RelativeCurvature::crossing) or on the minimum across the saddle goes back to the
    /// minimum on own_u's side. The owner sets it while the pair has another row (the minima
    /// of a split); a lone row is left to reach the saddle, where the global stage splits it.
    /// Off, an evaluation costs no relative curvature.
    bool keep_off_saddles = false;
    /// The side the row keeps to: its parameters where an evaluation last ended on a minimum
    /// (with keep_off_saddles; else on any converged extremum), or its seed.
    Eigen::Vector4d own_u = Eigen::Vector4d::Zero();
    int walks = 0;  ///< evaluations that went back to the row's own minimum
    const contact::SurfaceSurfaceExtremum& extremum() const override { return ext; }
    /// (The contact stands at u_new until the next evaluation: a second event before then is
    /// matched against it.)
    void Reseed(const Eigen::Vector4d& u_new) override {
      u = u_new;
      own_u = u_new;
      ext.u = u_new;
      valid = false;
      tracking = false;
    }
    /// The state of a term on another pair of surfaces (a BodyContactTerm's slot moved to
    /// another face pair): Reseed next. Allocation free.
    void Rebind(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g) {
      tracker.Rebind(f, g);
      valid = false;
      tracking = false;
    }
  };

  /// The surfaces must outlive the term. `seed`: (u, v, s, t) near the extremum to follow.
  SurfaceContactTerm(int body_f, const nurbs::NurbsSurface* f, int body_g,
                     const nurbs::NurbsSurface* g, const Eigen::Vector4d& seed,
                     const ContactTracking& tracking = {});

  std::string name() const override { return "surface_contact"; }
  int dim() const override { return 1; }
  int body_a() const override { return body_f_; }
  int body_b() const override { return body_g_; }
  bool Idle(const TermState* state) const override {
    return !static_cast<const State*>(state)->active;
  }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;

  std::unique_ptr<TermState> MakeState() const override;
  /// Gap plus a quarter of the pair's relative radius of curvature, 1/λ_max (RelativeCurvatureOf).
  bool Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const override;
  /// The default ContactTracking::accept_residual.
  static constexpr double kTrackedResidual = 1e-12;
  /// A row of a split pair whose evaluation moved its parameters farther than this (a fraction
  /// of the domains, contact::ParameterDistance) is checked for a hump of the distance on the
  /// way (Newton from beside a saddle may converge to the minimum across it).
  static constexpr double kHumpCheckStep = 1e-4;

 private:
  friend class TrimmedContactTerm;  // measures its face contact through this term
  void Update(const std::vector<BodyPose>& poses, State* st) const;
  /// ∇²β at an edge or corner extremum (contacts.cc), weighted by w, into *h.
  void AddBoundaryHessian(const State& st, const BodyPose& pf, const BodyPose& pg, double w,
                          TermHessian* h) const;

  int body_f_, body_g_;
  const nurbs::NurbsSurface* f_;
  const nurbs::NurbsSurface* g_;
  Eigen::Vector4d seed_;
  ContactTracking tracking_;
};

/// The signed distance from a point on body a (attachment point) to a surface on body b at the
/// closest point, (x − S)·n_S, one row: "point on surface" as an equality, "point above the
/// surface" as an inequality. Tracked and differentiated like SurfaceContactTerm.
class PointOnSurfaceTerm final : public Term {
 public:
  struct State final : TermState {
    Eigen::Vector2d u;
    Vector7d q_a, q_s;
    bool valid = false;
    FollowAnchor<Eigen::Vector2d> anchor;  ///< the line search's base point (TermState::Anchor)
    void Anchor(int slot) override { anchor.Keep(slot, u, q_a, q_s, valid); }
    void Rewind(int slot) override { anchor.Restore(slot, &u, &q_a, &q_s, &valid); }
    contact::PointSurfaceExtremum ext;
    contact::PlacedSurfacePoint eval;
    const contact::PointSurfaceExtremum& extremum() const { return ext; }
  };
  PointOnSurfaceTerm(const Attachment& point, int body_s, const nurbs::NurbsSurface* surface,
                     const Eigen::Vector2d& seed);

  std::string name() const override { return "point_on_surface"; }
  const Attachment& point() const { return point_; }
  int dim() const override { return 1; }
  int body_a() const override { return point_.body; }
  int body_b() const override { return body_s_; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;
  std::unique_ptr<TermState> MakeState() const override;

  /// The point's closest point on the surface at `poses` (solved when they changed).
  void Update(const std::vector<BodyPose>& poses, State* st) const;

 private:
  Attachment point_;
  int body_s_;
  const nurbs::NurbsSurface* s_;
  Eigen::Vector2d seed_;
};

namespace internal {
/// Derivative of the unit normal n = N/|N| along a parameter, from N's partial N_a.
Eigen::Vector3d UnitNormalPartial(const Eigen::Vector3d& N, const Eigen::Vector3d& N_a);
/// Adds w·sym(H), a Hessian over (q_a, q_b), into h's blocks (the contact terms' Hessians).
void Split(const Eigen::Matrix<double, 14, 14>& H, double w, TermHessian* h);
/// H += V_aᵀ x_a − V_bᵀ x_b for a contact row β = n·(p_a − p_b): the points' Jacobians changing
/// as their parameters move (x_a: Ka x 14, x_b: 2 x 14, over (q_a, q_b)). V = n·∂P/∂(parameter)
/// is rotational only, one row (t_W × n)ᵀΩ per world partial t_W (contact::DirectionGradient),
/// so only H's rows 3–6 and 10–13 change.
template <int Ka>
void AddPartialsHessian(const contact::BodyPose& pa, const Eigen::Matrix<double, 3, Ka>& partials_a,
                        const Eigen::Matrix<double, Ka, 14>& x_a, const contact::BodyPose& pb,
                        const Eigen::Matrix<double, 3, 2>& partials_b,
                        const Eigen::Matrix<double, 2, 14>& x_b, const Eigen::Vector3d& n,
                        Eigen::Matrix<double, 14, 14>* H);
/// ∇²β at fixed parameters' rotational curvature aside, for a row β = n·(p_a − p_b) measured along
/// surface b's unit normal n = N/|N| at an interior extremum (a surface pair's, a curve's against
/// a surface): Pᵀ n_q + V_aᵀ x_a − V_bᵀ x_b, with P = ∂(p_a − p_b)/∂q at fixed parameters and
/// n_q = [0, −[n]× Ω_b] + n_s x_b.row(0) + n_t x_b.row(1) (b's frame turning, its (s, t) moving).
/// Written by its nonzero blocks: of the 14 x 14 products 2/3 of the terms are known zeros.
template <int Ka>
Eigen::Matrix<double, 14, 14> NormalRowHessian(
    const Eigen::Matrix<double, 3, 14>& P, const contact::BodyPose& pa,
    const Eigen::Matrix<double, 3, Ka>& partials_a, const Eigen::Matrix<double, Ka, 14>& x_a,
    const contact::BodyPose& pb, const contact::PlacedSurfacePoint& b,
    const Eigen::Matrix<double, 2, 14>& x_b, const Eigen::Vector3d& n);
}  // namespace internal

std::shared_ptr<SurfaceContactTerm> MakeSurfaceContact(int body_f, const nurbs::NurbsSurface* f,
                                                       int body_g, const nurbs::NurbsSurface* g,
                                                       const Eigen::Vector4d& seed,
                                                       const ContactTracking& tracking = {});
std::shared_ptr<PointOnSurfaceTerm> MakePointOnSurface(const Attachment& point, int body_s,
                                                       const nurbs::NurbsSurface* surface,
                                                       const Eigen::Vector2d& seed);

}  // namespace tangent::optimizer
