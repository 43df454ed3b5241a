#pragma once

// The clearance guard (issue 33, "no tunnelling"; docs/stability.md "No tunnelling"): every
// Newton step is shortened so that no pair of bodies certified apart by the global stage
// (contact/clearance.h) can have come into contact anywhere along it.
//
// The certificate: at coordinates q_ref the watched surfaces of bodies a and b are at least c
// apart. A step moves each body along a segment of coordinates: its origin along a straight
// line, its rotation along a great arc of the quaternion sphere (the normalized step). A point
// x of body b (|x| ≤ r_b, its surfaces' reach about the body origin) is displaced from where it
// was at q_ref by at most
//
//   μ_b = max(|t₀ − t_ref|, |t₁ − t_ref|) + 2 sin(min(π, θ_ref,0 + θ_0,1) / 2) r_b
//
// at every point of the segment: |t − t_ref| is convex along the line, the rotation angle from
// R_ref is at most θ_ref,0 plus the arc's own angle (the triangle inequality of the angle
// metric), and |(R − R_ref) x| = 2 sin(θ/2)|x|. Distances are 1-Lipschitz in each body's points,
// so the pair stays at least c − μ_a − μ_b apart along the whole segment. The step is kept to
// μ_a + μ_b ≤ kShare · c: the surfaces stay at least (1 − kShare) c apart, and cannot cross.

#include <algorithm>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "optimizer/mechanism.h"

namespace tangent::optimizer {

class ClearanceGuard {
 public:
  /// The share of a pair's certified clearance a step may use.
  static constexpr double kShare = 0.9;

  /// `pairs`: body pairs (mechanism indices); `reach[b]`: the farthest point of body b's watched
  /// surfaces from its origin (m). Allocates; the guard is disarmed until a certificate comes.
  void Configure(const Mechanism& mechanism, std::vector<std::pair<int, int>> pairs,
                 std::vector<double> reach);
  /// Takes a certificate: `pose_ref(b)` the pose (7 coordinates, [p, Q]) of body b it was
  /// certified at, `clearance[k]` for pairs[k] (m; +∞: not certified, not guarded). Taken only
  /// when `q` (the coordinates now) lies within it: otherwise the guard keeps the one it has,
  /// which holds q (a step since was kept within it), and the next certificate, certified
  /// nearer q, is taken. Allocation free. @return whether it was taken.
  template <class PoseRef>
  bool Adopt(const Eigen::VectorXd& q, PoseRef&& pose_ref, const double* clearance) {
    for (size_t b = 0; b < reach_.size(); ++b) {
      const int o = mechanism_->offset(static_cast<int>(b));
      if (o >= 0) candidate_ref_.segment<7>(o) = pose_ref(static_cast<int>(b));
    }
    for (size_t k = 0; k < pairs_.size(); ++k) candidate_[k] = clearance[k];
    if (!Within(candidate_ref_, candidate_, q, q, 0.0)) return false;
    q_ref_.swap(candidate_ref_);
    clearance_.swap(candidate_);
    armed_ = false;
    for (double c : clearance_) armed_ = armed_ || c < kInfinity;
    return true;
  }
  bool armed() const { return armed_; }

  /// The largest fraction α ∈ [0, 1] of `step` from q (by bisection, to 2⁻²⁰) keeping every
  /// certified pair within its share; 1 when the whole step is. Allocation free.
  double Fraction(const Eigen::VectorXd& q, const Eigen::VectorXd& step) const;

  /// The largest fraction α ∈ [0, alpha] of `step` from q (by bisection, to 2⁻²⁰ of alpha)
  /// keeping every marked body's motion from q_ref (Motion, along the segment) within `bound`;
  /// alpha when the whole of it does. Allocation free.
  double MotionFraction(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q,
                        const Eigen::VectorXd& step, double alpha, double bound) const;
  /// Marks body b (or clears its mark) for MotionFraction. Allocation free.
  void Bound(int b, bool on) { bounded_[static_cast<size_t>(b)] = on; }
  void ClearBounds() { std::fill(bounded_.begin(), bounded_.end(), 0); }
  /// Marks body b (or clears its mark) for ReturnWithin: its steps are free, but a solve that
  /// does not converge returns no iterate that moved it farther than the bound. Allocation free.
  void BoundReturn(int b, bool on) { return_bounded_[static_cast<size_t>(b)] = on; }
  void ClearReturnBounds() { std::fill(return_bounded_.begin(), return_bounded_.end(), 0); }
  /// Whether every body marked by BoundReturn is within `bound` of q_ref at q (Motion, at the
  /// point q). Allocation free.
  bool ReturnWithin(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q, double bound) const;

  /// μ_b of the header for the segment q → q + α step against q_ref (0 for a fixed body).
  double Motion(int b, const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q,
                const Eigen::VectorXd& step, double alpha) const;

  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  const std::vector<double>& clearance() const { return clearance_; }

 private:
  static constexpr double kInfinity = 1e300;
  /// Whether every certified pair stays within its share along q → q + α step.
  bool Within(const Eigen::VectorXd& q_ref, const std::vector<double>& clearance,
              const Eigen::VectorXd& q, const Eigen::VectorXd& step, double alpha) const;

  const Mechanism* mechanism_ = nullptr;
  std::vector<std::pair<int, int>> pairs_;
  std::vector<double> reach_;
  Eigen::VectorXd q_ref_, candidate_ref_;
  std::vector<char> bounded_;         ///< per body: MotionFraction bounds it
  std::vector<char> return_bounded_;  ///< per body: ReturnWithin bounds it
  std::vector<double> clearance_, candidate_;
  bool armed_ = false;
};

}  // namespace tangent::optimizer
