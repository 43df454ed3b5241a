#pragma once

#include <vector>

#include <Eigen/Core>

#include "optimizer/problem.h"

namespace tangent::optimizer {

/// Evaluates a Problem's terms at q into dense stacked arrays: equality values c_E and Jacobian
/// J_E, inequalities c_I, J_I, objective residuals r_O, J_O (rows as in Problem::Entry::row,
/// n = 7 x moving bodies columns). Storage is sized at construction; Evaluate allocates nothing.
/// Shared by the solver and by the adapters that hand the same problem to peer solvers.
class ProblemEvaluator {
 public:
  explicit ProblemEvaluator(const Problem& problem);

  void Evaluate(const Eigen::VectorXd& q);

  /// E(q) = ½ w_la (q − q_ref)ᵀ M (q − q_ref) + Σ ½ w |r|² with the values of the last Evaluate.
  double Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                   const Eigen::MatrixXd& M) const;
  /// ∇E into *g (same conventions).
  void ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                         const Eigen::MatrixXd& M, Eigen::VectorXd* g) const;
  /// Adds Σ_entries Σ_rows weight_row ∇²r_row (terms with second derivatives) to *H at the
  /// bodies' blocks; `weights` is indexed like the stacked rows of `list`.
  void AddCurvature(const std::vector<Problem::Entry>& list, const Eigen::VectorXd& weights,
                    Eigen::MatrixXd* H) const;

  const Problem& problem() const { return problem_; }
  const std::vector<BodyPose>& poses() const { return poses_; }
  const Eigen::VectorXd& c_e() const { return c_e_; }
  const Eigen::VectorXd& c_i() const { return c_i_; }
  const Eigen::VectorXd& r_o() const { return r_o_; }
  const Eigen::MatrixXd& J_e() const { return J_e_; }
  const Eigen::MatrixXd& J_i() const { return J_i_; }
  const Eigen::MatrixXd& J_o() const { return J_o_; }

 private:
  const Problem& problem_;
  std::vector<BodyPose> poses_;
  Eigen::VectorXd c_e_, c_i_, r_o_;
  Eigen::MatrixXd J_e_, J_i_, J_o_;
  mutable Eigen::MatrixXd scratch_a_, scratch_b_;
};

}  // namespace tangent::optimizer
