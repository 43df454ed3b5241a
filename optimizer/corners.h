#pragma once

// A corner of a flat face against another face (docs/contact.md, "Face contacts";
// contact/face_gap.h): the signed distance from the corner, a fixed point of its body, to the
// other surface along its normal at the closest point, one inequality row β ≥ 0. Two flat faces
// are held by the corners of each that lie over the other: the height of one face above the
// other's plane is affine along it, so it is least at such a corner (or where their edges cross,
// which these rows do not measure).
//
// The row is optimizer::PointOnSurfaceTerm's (its closed-form gradient and Hessian), with two
// states added: in use or not (a face pair the global stage has not found: nothing is
// evaluated), and over the face or not (the corner's closest point on the other surface inside
// its domain; a corner beyond the other face's edge holds nothing and reads
// ContactSlotState::kInactiveDistance).

#include <memory>

#include "optimizer/contacts.h"
#include "optimizer/term.h"

namespace tangent::optimizer {

class CornerContactTerm final : public Term {
 public:
  struct State final : TermState {
    bool active = false;
    PointOnSurfaceTerm::State point;
    /// The corner lies over the other face (evaluated and converged inside its domain).
    bool over() const {
      return active && point.valid && point.ext.status == contact::ExtremalStatus::kConverged;
    }
    /// In use, its closest point followed from `seed` (the other surface's parameters).
    void Activate(const Eigen::Vector2d& seed) {
      active = true;
      point.u = seed;
      point.valid = false;
    }
    void Deactivate() { active = false; }
    void Anchor(int slot) override { point.Anchor(slot); }
    void Rewind(int slot) override { point.Rewind(slot); }
  };

  /// `corner` is the corner's point on its body; `seed` where its closest point on `surface` is
  /// first sought. The surface must outlive the term.
  CornerContactTerm(const Attachment& corner, int body_s, const nurbs::NurbsSurface* surface,
                    const Eigen::Vector2d& seed);

  std::string name() const override { return "corner_contact"; }
  int dim() const override { return 1; }
  int body_a() const override { return point_.body_a(); }
  int body_b() const override { return point_.body_b(); }
  const Attachment& corner() const { return point_.point(); }
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

 private:
  PointOnSurfaceTerm point_;
  Eigen::Vector2d seed_;
};

std::shared_ptr<CornerContactTerm> MakeCornerContact(const Attachment& corner, int body_s,
                                                     const nurbs::NurbsSurface* surface,
                                                     const Eigen::Vector2d& seed);

}  // namespace tangent::optimizer
