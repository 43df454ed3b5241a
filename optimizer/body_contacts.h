#pragma once

// Contact between two multi-face bodies (docs/cad.md, "Contact between bodies"): a scene says
// "these two parts may touch", and the global stage finds where, on whichever of their faces.
// The servo keeps a few contact slots for the body pair; each slot is a BodyContactTerm, one
// inequality row whose face pair is per-solve data, moved by the server when the global stage
// adds a contact on a face pair. Memory grows with the faces (one table entry each, its trim's
// edges built once) and the slots, never with the face pairs.

#include <memory>
#include <optional>
#include <vector>

#include "contact/trimmed.h"
#include "nurbs/surface.h"
#include "nurbs/trim.h"
#include "optimizer/contacts.h"
#include "optimizer/term.h"
#include "optimizer/trims.h"

namespace tangent::optimizer {

/// One face of a body that may touch another: its surface, its material when trimmed, and that
/// trim's edges ready for curve–surface solves (made once per face, shared by every slot).
struct ContactFace {
  int id = -1;    ///< the caller's name for the face (the server's surface index); ids order faces
  int body = -1;  ///< Mechanism body index
  const nurbs::NurbsSurface* surface = nullptr;
  const nurbs::TrimmedDomain* trim = nullptr;       ///< null: untrimmed
  std::shared_ptr<const contact::TrimEdges> edges;  ///< when trimmed
};
/// A face entry; builds its trim's edges. The surface and the trim must outlive the entry.
ContactFace MakeContactFace(int id, int body, const nurbs::NurbsSurface* surface,
                            const nurbs::TrimmedDomain* trim);

/// The signed distance β between two bodies at one extremal contact of one of their face pairs,
/// one row; as an inequality β ≥ 0, non-penetration. Which face pair is per-solve data (State):
/// Target() moves a slot to a face pair, then Activate() seeds it. On a face pair the slot is
/// exactly the face-pair contact a scene could declare on its own: a SurfaceContactTerm, or a
/// TrimmedContactTerm measuring the trimmed face's material (with both trimmed, the face of
/// lower id: the rule of declared face pairs, docs/trimming.md), evaluated, differentiated and
/// tracked by that term's own code. The row's Jacobian blocks and Hessian are in this term's
/// body order whichever face the inner term calls f.
class BodyContactTerm final : public Term {
 public:
  struct State final : ContactSlotState {
    /// The face pair measured: faces() indices, f the inner term's f (the one whose trim is
    /// measured), or −1 before the first Target().
    int f = -1, g = -1;
    bool trimmed = false;  ///< the inner term is `cut`, else `plain`
    bool swapped = false;  ///< f is on body b (the inner term's blocks are swapped)
    /// The inner terms (re-pointed by Target(), allocation free) and their states (made once).
    std::optional<SurfaceContactTerm> plain;
    std::optional<TrimmedContactTerm> cut;
    std::unique_ptr<TermState> plain_state, cut_state;

    ContactSlotState& inner() const {
      return static_cast<ContactSlotState&>(trimmed ? *cut_state : *plain_state);
    }
    const Term& inner_term() const {
      return trimmed ? static_cast<const Term&>(*cut) : static_cast<const Term&>(*plain);
    }
    /// The contact in the inner term's order: (u, v) on face f, (s, t) on face g.
    const contact::SurfaceSurfaceExtremum& extremum() const override { return inner().extremum(); }
    void Reseed(const Eigen::Vector4d& u_new) override { inner().Reseed(u_new); }
    void Anchor(int slot) override { inner().Anchor(slot); }
    void Rewind(int slot) override { inner().Rewind(slot); }
    /// The counters of both inner states, summed (ContactSlotState's).
    void SumCounters();
  };

  /// `faces_a` on one body, `faces_b` on another (each non-empty, ids distinct); the surfaces
  /// and trims must outlive the term. @throws std::invalid_argument.
  BodyContactTerm(std::vector<ContactFace> faces_a, std::vector<ContactFace> faces_b,
                  const ContactTracking& tracking = {});

  std::string name() const override { return "body_contact"; }
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
  /// The inner term's (a point does not depend on the bodies' order).
  bool Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const override;

  /// The face with this id, or −1 (a linear scan: faces are few, events rare).
  int FaceIndex(int id) const;
  /// Moves the slot to the face pair with ids (x, y), one on each body, in either order; the
  /// slot is then to be seeded (Activate) with parameters in the order (face f, face g).
  /// Allocation free. @return false (nothing changed) when they are not such a pair.
  bool Target(State* st, int id_x, int id_y) const;
  const std::vector<ContactFace>& faces() const { return faces_; }

 private:
  int body_a_, body_b_;
  std::vector<ContactFace> faces_;  ///< body a's, then body b's
  ContactTracking tracking_;
};

std::shared_ptr<BodyContactTerm> MakeBodyContact(std::vector<ContactFace> faces_a,
                                                 std::vector<ContactFace> faces_b,
                                                 const ContactTracking& tracking = {});

}  // namespace tangent::optimizer
