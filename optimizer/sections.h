#pragma once

// A section of a line contact (docs/contact.md, "Line contacts"): the signed distance between a
// parameter line of a surface f on body a, E(τ) = f(u₀, τ) (or f(τ, v₀)), and a surface g on
// body b, at their curve–surface extremum, one inequality row β ≥ 0.
//
// Where two surfaces meet along a line (a wire in a hook's bend, a shaft in a groove) their
// relative curvature is singular along the line, the one extremal point of the pair is
// degenerate there (a pitchfork: it turns into a saddle with a minimum either side) and one row
// at it cannot hold the pair. Two sections across the line, either side of the contact, can:
// each is a curve against a surface that crosses it, a regular extremum whatever the pair's
// curvature along the line, and each is an exact constraint (the section's points are f's
// points, so β ≥ 0 on it is necessary for the pair to be apart). The section's line is body
// fixed between placements (Place()), so its row is differentiated exactly like a trim edge's
// (curve_rows.h): no derivative of the placement enters.
//
// Per-solve data (State): whether the section is in use, its line and its tracked extremum.
// An inactive section evaluates nothing and reads β = ContactSlotState::kInactiveDistance.

#include <memory>

#include "contact/extremal.h"
#include "contact/placed.h"
#include "nurbs/surface.h"
#include "optimizer/contacts.h"
#include "optimizer/term.h"

namespace tangent::optimizer {

class SectionContactTerm final : public Term {
 public:
  struct State final : TermState {
    bool active = false;
    int fixed = 0;       ///< f's parameter held on the line: 0 u, 1 v
    double value = 0.0;  ///< its value
    Eigen::Vector3d u;   ///< tracked (s, t, τ): g's parameters, then the line's
    Vector7d q_a, q_b;
    bool valid = false;
    FollowAnchor<Eigen::Vector3d> anchor;  ///< the line search's base point (TermState::Anchor)
    void Anchor(int slot) override { anchor.Keep(slot, u, q_a, q_b, valid); }
    void Rewind(int slot) override { anchor.Restore(slot, &u, &q_a, &q_b, &valid); }
    contact::CurveSurfaceExtremum ext;
    contact::CurveSurfaceEval eval;
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();  ///< what β is measured along
    /// What β must reach (m): the row is β − margin ≥ 0. A line's sections hold their pair's
    /// estimate of how far the gap dips between them (server/line_contacts.h); 0 otherwise.
    double margin = 0.0;
    int64_t solves = 0;
    /// Puts the section on f's line (fixed, value), its extremum followed from (s, t, τ) = seed.
    void Place(int fixed_in, double value_in, const Eigen::Vector3d& seed) {
      active = true;
      fixed = fixed_in;
      value = value_in;
      u = seed;
      valid = false;
    }
    void Deactivate() { active = false; }
  };

  /// The surfaces must outlive the term.
  SectionContactTerm(int body_f, const nurbs::NurbsSurface* f, int body_g,
                     const nurbs::NurbsSurface* g);

  std::string name() const override { return "section_contact"; }
  int dim() const override { return 1; }
  int body_a() const override { return body_f_; }
  int body_b() const override { return body_g_; }
  const nurbs::NurbsSurface& f() const { return *f_; }
  const nurbs::NurbsSurface& g() const { return *g_; }
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
  bool Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const override;
  /// The section's extremum at `poses` (evaluates when they changed). Allocation free.
  void Update(const std::vector<BodyPose>& poses, State* st) const;

 private:
  int body_f_, body_g_;
  const nurbs::NurbsSurface* f_;
  const nurbs::NurbsSurface* g_;
};

std::shared_ptr<SectionContactTerm> MakeSectionContact(int body_f, const nurbs::NurbsSurface* f,
                                                       int body_g, const nurbs::NurbsSurface* g);

}  // namespace tangent::optimizer
