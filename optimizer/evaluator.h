#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "optimizer/block_matrix.h"
#include "optimizer/problem.h"

namespace tangent::optimizer {

/// Evaluates a Problem's terms at q. Values are stacked per kind (equalities c_E, inequalities
/// c_I, objective residuals r_O; rows as in Problem::Entry::row); Jacobians are kept as each
/// term's two 7-column blocks, and the products the solver needs (Jᵀv, Jx, JᵀDJ, the weighted
/// curvature) are formed block by block into a BlockMatrix. With `dense_jacobians`, Evaluate
/// also fills the dense stacked Jacobians (J_e(), J_i(), J_o()) that peer-solver adapters want.
/// Storage is sized at construction; Evaluate and the products allocate nothing. It owns the
/// problem's per-solve data (ProblemData), so evaluators of one Problem may run on different
/// threads.
class ProblemEvaluator {
 public:
  enum Kind { kEquality = 0, kInequality = 1, kObjective = 2 };

  explicit ProblemEvaluator(const Problem& problem, bool dense_jacobians = true);

  void Evaluate(const Eigen::VectorXd& q);
  /// Evaluates the equality rows only (values, Jacobians, the dense J_e()): what a measure made
  /// of the constraint Jacobian needs (Dexterity); the other kinds keep their last values.
  void EvaluateEqualities(const Eigen::VectorXd& q);
  /// *J = the kind's stacked Jacobian at the last Evaluate, dense (rows × coordinates), from the
  /// terms' blocks.
  void DenseJacobian(Kind kind, Eigen::MatrixXd* J) const;

  /// Body pairs (moving-body block indices) coupled by some term, for BlockMatrix's pattern.
  std::vector<std::pair<int, int>> CoupledBlocks() const;

  /// E(q) = ½ w_la (q − q_ref)ᵀ M (q − q_ref) + Σ ½ w |r|² with the values of the last Evaluate;
  /// M as 7 x 7 blocks per moving body (Mechanism::MetricBlocks).
  double Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                   const std::vector<Matrix7d>& M) const;
  /// ∇E into *g; with `design`, also the design objectives' share of it, −Σ w ∇f (offline).
  void ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                         const std::vector<Matrix7d>& M, Eigen::VectorXd* g,
                         Eigen::VectorXd* design = nullptr) const;
  /// *g += scale · J_kindᵀ v (v indexed like the kind's stacked rows).
  void AddJacobianTransposeTimes(Kind kind, const Eigen::VectorXd& v, double scale,
                                 Eigen::VectorXd* g) const;
  /// Keeps the equality and inequality Jacobians of the last evaluation (where a Newton matrix
  /// was built: the solver's finishing correction multiplies by them after later evaluations).
  void KeepJacobians();
  /// g += scale · J_keptᵀ v (equality or inequality rows, as kept by KeepJacobians).
  void AddKeptJacobianTransposeTimes(Kind kind, const Eigen::VectorXd& v, double scale,
                                     Eigen::VectorXd* g) const;
  /// *out = J_kind x.
  void JacobianTimes(Kind kind, const Eigen::VectorXd& x, Eigen::VectorXd* out) const;
  /// H += J_kindᵀ diag(row_weights) J_kind.
  void AddGaussNewton(Kind kind, const Eigen::VectorXd& row_weights, BlockMatrix* H) const;
  /// H += Σ_rows weight_row ∇²r_row for the kind's terms with second derivatives. Rotation
  /// curvature is accumulated per body and folded by FoldRotations (call it once, after the
  /// last AddCurvature of a matrix).
  void AddCurvature(Kind kind, const Eigen::VectorXd& weights, BlockMatrix* H);
  void FoldRotations(BlockMatrix* H);
  /// Dense variants for peer adapters: M and H dense n x n.
  double Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                   const Eigen::MatrixXd& M) const;
  void ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                         const Eigen::MatrixXd& M, Eigen::VectorXd* g) const;
  /// *g += Σ_rows ∇²r_row · Y.row(row)ᵀ over the kind's terms with second derivatives (Y: the
  /// kind's rows × coordinates): each row's Hessian times its own direction, i.e. the gradient
  /// of ⟨Y, J_kind(q)⟩ at fixed Y. One weighted Hessian per row whose direction is not zero,
  /// folded per term; no n × n matrix is formed. (Dexterity's gradients.)
  void AddRowHessiansTimes(Kind kind, const Eigen::MatrixXd& Y, Eigen::VectorXd* g);
  /// H += Σ w ∇²r over `list`'s kind (dense H; folds its rotations itself).
  void AddCurvature(const std::vector<Problem::Entry>& list, const Eigen::VectorXd& weights,
                    Eigen::MatrixXd* H);

  /// TermState::Anchor / Rewind on every state of a row in use (a trial's base point, or the
  /// solve's best iterate).
  void AnchorStates(int slot) { ForEachBusyState(&TermState::Anchor, slot); }
  void RewindStates(int slot) { ForEachBusyState(&TermState::Rewind, slot); }

  const Problem& problem() const { return problem_; }
  /// The terms' per-solve states (contacts' tracked parameters, goal targets).
  ProblemData& data() { return data_; }
  const ProblemData& data() const { return data_; }
  const std::vector<BodyPose>& poses() const { return poses_; }
  const Eigen::VectorXd& values(Kind kind) const { return values_[kind]; }
  const Eigen::VectorXd& c_e() const { return values_[kEquality]; }
  const Eigen::VectorXd& c_i() const { return values_[kInequality]; }
  const Eigen::VectorXd& r_o() const { return values_[kObjective]; }
  /// Dense stacked Jacobians (only with dense_jacobians).
  const Eigen::MatrixXd& J_e() const { return dense_[kEquality]; }
  const Eigen::MatrixXd& J_i() const { return dense_[kInequality]; }
  const Eigen::MatrixXd& J_o() const { return dense_[kObjective]; }

 private:
  struct Item {
    const Term* term = nullptr;
    TermState* state = nullptr;
    double weight = 1.0;
    int row = 0, dim = 0;
    int body_a = -1, body_b = -1;    // mechanism body indices
    int block_a = -1, block_b = -1;  // moving-body block indices (−1: fixed or none)
    /// The term was idle (Term::Idle) at the last evaluation, and its row is written: a
    /// constant value and zero Jacobian rows, which the products and sums below skip.
    bool idle = false;
    bool kept_idle = true;  ///< idle when KeepJacobians last kept the rows
  };
  const std::vector<Problem::Entry>& List(Kind kind) const;

  const Problem& problem_;
  ProblemData data_;
  bool dense_jacobians_;
  std::vector<BodyPose> poses_;
  std::array<std::vector<Item>, 3> items_;
  std::array<Eigen::VectorXd, 3> values_;
  using JacobianRows = Eigen::Matrix<double, Eigen::Dynamic, 7>;
  std::array<JacobianRows, 3> J_a_, J_b_;
  std::array<JacobianRows, 3> kept_a_, kept_b_;  ///< KeepJacobians (objective rows unused)
  std::array<Eigen::MatrixXd, 3> dense_;
  void EvaluateKinds(const Eigen::VectorXd& q, int first, int last);
  void ForEachBusyState(void (TermState::*f)(int), int slot);
  std::vector<Eigen::Matrix3d> rotation_weights_;  // per moving block
  bool rotations_pending_ = false;
};

}  // namespace tangent::optimizer
