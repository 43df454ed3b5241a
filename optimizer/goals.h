#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "optimizer/joints.h"
#include "optimizer/problem.h"

namespace tangent::optimizer {

/// Goals of seed 002 §5 as terms: usable as weighted objectives (½ w |r|²) or hard constraints.
/// Position: P − target (3 rows). The target is per-solve data (each servo tick: the hand):
/// `data.Of(goal).target = x` on the solving ProblemData; the constructor's is the initial one.
class PositionGoalTerm final : public Term {
 public:
  struct State final : TermState {
    Eigen::Vector3d target;  ///< world (m)
  };
  PositionGoalTerm(const Attachment& at, const Eigen::Vector3d& target_W)
      : at_(at), initial_target_(target_W) {}
  /// The target a new state starts with.
  const Eigen::Vector3d& initial_target() const { return initial_target_; }
  std::string name() const override { return "position_goal"; }
  int dim() const override { return 3; }
  int body_a() const override { return at_.body; }
  std::unique_ptr<TermState> MakeState() const override;
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;

 private:
  Attachment at_;
  Eigen::Vector3d initial_target_;
};
/// Moves a position goal's target in a solve's data: `SetGoalTarget(solver.data(), *goal, x)`.
inline void SetGoalTarget(ProblemData& data, const PositionGoalTerm& goal,
                          const Eigen::Vector3d& target_W) {
  data.Of(goal).target = target_W;
}
std::shared_ptr<PositionGoalTerm> MakePositionGoal(const Attachment& at,
                                                   const Eigen::Vector3d& target_W);
TermPtr PositionGoal(const Attachment& at, const Eigen::Vector3d& target_W);
/// Orientation with per-axis weights: w_i (R e_i − R_target e_i), i = x, y, z (9 rows; a zero
/// weight frees rotation that moves that axis only through the others). The target is per-solve
/// data like PositionGoalTerm's (each servo tick of a 6-DOF device: the stylus); set it through
/// SetTarget, which checks it.
class OrientationGoalTerm final : public Term {
 public:
  struct State final : TermState {
    Eigen::Matrix3d R_target;  ///< world
  };
  /// @throws std::invalid_argument when R_target is not a rotation.
  OrientationGoalTerm(int body, const Eigen::Matrix3d& R_target, const Eigen::Vector3d& weights);
  /// Moves the target in `state`. @pre a rotation (checked by the constructor only: the servo
  /// passes normalized quaternions' matrices).
  static void SetTarget(State* state, const Eigen::Matrix3d& R_target) {
    state->R_target = R_target;
  }
  std::string name() const override { return "orientation_goal"; }
  int dim() const override { return 9; }
  int body_a() const override { return body_; }
  std::unique_ptr<TermState> MakeState() const override;
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;

 private:
  int body_;
  Eigen::Matrix3d initial_R_;
  Eigen::Vector3d w_;
};
TermPtr OrientationGoal(int body, const Eigen::Matrix3d& R_target, const Eigen::Vector3d& weights);
std::shared_ptr<OrientationGoalTerm> MakeOrientationGoal(int body, const Eigen::Matrix3d& R_target,
                                                         const Eigen::Vector3d& weights);
/// Position and orientation together (3 + 9 rows).
TermPtr PoseGoal(const Attachment& at, const Eigen::Vector3d& target_W,
                 const Eigen::Matrix3d& R_target, const Eigen::Vector3d& weights);
/// Aiming: the body direction `at.axis` from `at.point` points at target_W:
/// R axis − (target − P)/|target − P| (3 rows).
TermPtr AimingGoal(const Attachment& at, const Eigen::Vector3d& target_W);
/// Line: P on the line through `origin` along `direction`: (I − d dᵀ)(P − origin) (3 rows).
TermPtr LineGoal(const Attachment& at, const Eigen::Vector3d& origin,
                 const Eigen::Vector3d& direction);
/// Plane: n·(P − origin) (1 row).
TermPtr PlaneGoal(const Attachment& at, const Eigen::Vector3d& origin,
                  const Eigen::Vector3d& normal);
/// Half-space n·(P − origin) ≥ 0. As a constraint the row is n·(P − origin); as an objective
/// the residual is min(0, n·(P − origin)) (one-sided), so it only acts when violated.
TermPtr HalfSpaceGoal(const Attachment& at, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& normal, bool one_sided);
/// Disjunction: the goal among `goals` with the smallest |r|² is the active one; its residual is
/// returned, zero-padded to the largest goal's dimension. Not differentiable where the active
/// goal switches (the solver sees a different goal from then on).
TermPtr DisjunctionGoal(std::vector<TermPtr> goals);
/// r(q) − rhs (rhs: dim values): the constraint r(q) = rhs (or ≥ rhs) of a design study, whose
/// multiplier is the optimum's sensitivity to rhs. Jacobians and curvature are r's. The rhs is
/// per-solve data (a sweep moves it case by case on one shared problem): ShiftedState, made with
/// the given rhs, holds it and r's own state.
TermPtr Shifted(TermPtr term, const Eigen::VectorXd& rhs);
struct ShiftedState final : TermState {
  std::unique_ptr<TermState> inner;  ///< r's state (nullptr for a stateless r)
  Eigen::VectorXd rhs;
  void Anchor(int slot) override {
    if (inner) inner->Anchor(slot);
  }
  void Rewind(int slot) override {
    if (inner) inner->Rewind(slot);
  }
};

}  // namespace tangent::optimizer
