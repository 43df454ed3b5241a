#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "optimizer/mechanism.h"

namespace tangent::optimizer {

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
  /// r(q) and ∂r/∂q_a, ∂r/∂q_b (dim x 7 each). Allocation free.
  virtual void Evaluate(const std::vector<BodyPose>& poses, Eigen::Ref<Eigen::VectorXd> r,
                        Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const = 0;

  using Matrix7d = Eigen::Matrix<double, 7, 7>;
  /// Adds Σ_i w_i ∇²r_i, the rows' second derivatives weighted by w (dim), to the blocks
  /// H_aa, H_ab (rows a, columns b) and H_bb. A term that returns false from has_hessian() adds
  /// nothing: its curvature is then missing from the solver's Newton matrix (Gauss–Newton).
  virtual bool has_hessian() const { return false; }
  virtual void AddWeightedHessian(const std::vector<BodyPose>& /*poses*/,
                                  const Eigen::Ref<const Eigen::VectorXd>& /*w*/,
                                  Matrix7d* /*H_aa*/, Matrix7d* /*H_ab*/,
                                  Matrix7d* /*H_bb*/) const {}
};

using TermPtr = std::shared_ptr<const Term>;

}  // namespace tangent::optimizer
