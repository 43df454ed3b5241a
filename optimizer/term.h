#pragma once

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "base/check.h"
#include "optimizer/mechanism.h"

namespace tangent::optimizer {

using Matrix7d = Eigen::Matrix<double, 7, 7>;

/// The pose of body `body` in a pose array (the terms' one way of indexing it: checked in debug
/// and sanitizer builds; Problem::Add has checked the index against the mechanism).
inline const BodyPose& PoseOf(const std::vector<BodyPose>& poses, int body) {
  TANGENT_DCHECK(body >= 0 && static_cast<size_t>(body) < poses.size());
  return poses[static_cast<size_t>(body)];
}

/// Whether two poses are the same coordinates, bit for bit (a term's cached evaluation is
/// reused only then).
inline bool SamePose(const Vector7d& a, const Vector7d& b) {
  return (a.array() == b.array()).all();
}

/// The second derivatives a term adds for its bodies a and b: 7 x 7 blocks (rows a, columns b
/// for ab) and, for the curvature of rotated body vectors, rotation weights: a term whose value
/// contains yᵀ R_a v adds y vᵀ to W_a instead of a 4 x 4 block, and the owner folds each body's
/// W once with contact::RotateHessianWeighted (the Hessian is linear in y vᵀ), so a joint's
/// rows cost one fold per body per Newton matrix, not one per row.
struct TermHessian {
  Matrix7d aa, ab, bb;
  Eigen::Matrix3d W_a, W_b;
  void SetZero() {
    aa.setZero();
    ab.setZero();
    bb.setZero();
    W_a.setZero();
    W_b.setZero();
  }
  /// Folds W_a and W_b into aa and bb (Q_a, Q_b the bodies' quaternion coordinates) and clears
  /// them.
  void Fold(const Eigen::Vector4d& Q_a, const Eigen::Vector4d& Q_b);
  /// Adds a Hessian taken over the bodies in the other order, (b, a): its blocks
  /// [[bb, baᵀ], [ba, aa]] swapped into this one's (a, b).
  void AddSwapped(const TermHessian& other) {
    aa += other.bb;
    bb += other.aa;
    ab += other.ab.transpose();
    W_a += other.W_b;
    W_b += other.W_a;
  }
};

/// The anchors a state keeps (TermState::Anchor). The solver anchors each line search's base
/// point, alternating between the two so that the best iterate's (what an unconverged solve
/// returns) is never overwritten by a later one's.
inline constexpr int kAnchorSlots = 2;

/// The per-solve state of a term: whatever changes while a problem is solved (a contact's
/// tracked parameters and cached evaluation, a goal's target, scratch). A Term itself is
/// immutable after construction and may be shared by threads; each solve owns the states of
/// its problem's terms in a ProblemData (problem.h), made once, so evaluation allocates nothing.
class TermState {
 public:
  virtual ~TermState() = default;
  /// A point the solve may come back to (slot < kAnchorSlots): what Rewind(slot) returns to. A
  /// state that follows something along the poses (a contact's tracked extremum) keeps where it
  /// stood there; a trial point the line search rejects must not be where the next, shorter trial
  /// starts from, nor a later iterate's extremum (perhaps another branch of its pair) where the
  /// best iterate, returned, is evaluated from.
  virtual void Anchor(int /*slot*/) {}
  virtual void Rewind(int /*slot*/) {}
};

/// What a state that follows an extremum along the poses keeps at an anchor (TermState::Anchor,
/// one per slot): its parameters, the two poses it was evaluated at and whether it was.
/// Restore puts them back and marks the state `rewound`: its cached answer is another point's,
/// so its next Update solves afresh (from the anchor's parameters) whatever the poses.
template <class Params>
struct FollowAnchor {
  struct Kept {
    Params u{};
    Vector7d q_a = Vector7d::Zero(), q_b = Vector7d::Zero();
    bool valid = false;
  };
  Kept kept[kAnchorSlots];
  bool rewound = false;
  void Keep(int slot, const Params& u_in, const Vector7d& qa, const Vector7d& qb, bool valid_in) {
    Kept& k = kept[slot];
    k.u = u_in;
    k.q_a = qa;
    k.q_b = qb;
    k.valid = valid_in;
  }
  void Restore(int slot, Params* u_out, Vector7d* qa, Vector7d* qb, bool* valid_out) {
    const Kept& k = kept[slot];
    *u_out = k.u;
    *qa = k.q_a;
    *qb = k.q_b;
    *valid_out = k.valid;
    rewound = true;
  }
  /// Whether the state's last answer stands for poses (a, b), so that Update may return it;
  /// when not, Update solves afresh and the rewound mark is spent.
  bool Stands(bool valid_now, const Vector7d& a, const Vector7d& a_then, const Vector7d& b,
              const Vector7d& b_then) {
    if (valid_now && !rewound && SamePose(a, a_then) && SamePose(b, b_then)) return true;
    rewound = false;
    return false;
  }
};

/// A smooth vector function r(q) of the poses of at most two bodies, with its Jacobian in two
/// 7-column blocks (one per body; a fixed body's block is ignored). Joints, limits and goals
/// are all terms; a Problem decides whether a term is an equality (r = 0), an inequality
/// (r ≥ 0) or a weighted least-squares objective (½ w |r|²).
class Term {
 public:
  virtual ~Term() = default;
  virtual std::string name() const = 0;
  virtual int dim() const = 0;
  /// Body indices (Mechanism) the term depends on; b may be −1.
  virtual int body_a() const = 0;
  virtual int body_b() const { return -1; }
  /// A fresh per-solve state, or nullptr for a term without one (its Evaluate ignores `state`).
  virtual std::unique_ptr<TermState> MakeState() const { return nullptr; }
  /// r(q) and ∂r/∂q_a, ∂r/∂q_b (dim x 7 each), `state` the term's own (from MakeState; nullptr
  /// exactly when MakeState returns nullptr). Allocation free.
  virtual void Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                        Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                        Eigen::Ref<Eigen::MatrixXd> J_b) const = 0;

  /// Whether the row is idle: constant, with a zero Jacobian and no curvature, whatever the
  /// poses (a free contact slot). An evaluator may then skip the term once its row is written.
  virtual bool Idle(const TermState* /*state*/) const { return false; }

  /// Adds Σ_i w_i ∇²r_i, the rows' second derivatives weighted by w (dim), to *h. A term that
  /// returns false from has_hessian() adds nothing: its curvature is then missing from the
  /// solver's Newton matrix (Gauss–Newton).
  virtual bool has_hessian() const { return false; }
  virtual void AddWeightedHessian(const std::vector<BodyPose>& /*poses*/, TermState* /*state*/,
                                  const Eigen::Ref<const Eigen::VectorXd>& /*w*/,
                                  TermHessian* /*h*/) const {}

  /// A contact row's reach (the solver's step bound, docs/stability.md "Step reach"), at the
  /// state's last evaluation: the world point p where it measures and how far (m) one solver
  /// step may move the two bodies' copies of p relative to each other, so that the row's
  /// extremum is continued and not jumped over. false: no bound (not a contact, inactive, or
  /// flat). Allocation free.
  virtual bool Reach(const TermState* /*state*/, Eigen::Vector3d* /*p*/, double* /*reach*/) const {
    return false;
  }
};

/// The reach of a contact measured at distance β between two points whose relative radius of
/// curvature is 1/κ (κ > 0): its gap, and a quarter of that radius (an extremum moves along the
/// surfaces by about the relative motion times the radius over the gap's scale, so a step within
/// a quarter radius keeps it in its basin). 0 < κ; else no bound (+inf).
inline double ContactReach(double beta, double kappa) {
  return kappa > 0.0 ? std::max(beta, 0.0) + 0.25 / kappa : std::numeric_limits<double>::infinity();
}

using TermPtr = std::shared_ptr<const Term>;

}  // namespace tangent::optimizer
