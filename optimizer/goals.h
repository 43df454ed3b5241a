#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "optimizer/joints.h"

namespace tangent::optimizer {

/// Goals of seed 002 §5 as terms: usable as weighted objectives (½ w |r|²) or hard constraints.
/// Position: P − target (3 rows). The target moves with set_target (each servo tick: the hand).
class PositionGoalTerm final : public Term {
 public:
  PositionGoalTerm(const Attachment& at, const Eigen::Vector3d& target_W)
      : at_(at), target_(target_W) {}
  void set_target(const Eigen::Vector3d& target_W) { target_ = target_W; }
  const Eigen::Vector3d& target() const { return target_; }
  std::string name() const override { return "position_goal"; }
  int dim() const override { return 3; }
  int body_a() const override { return at_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;

 private:
  Attachment at_;
  Eigen::Vector3d target_;
};
std::shared_ptr<PositionGoalTerm> MakePositionGoal(const Attachment& at,
                                                   const Eigen::Vector3d& target_W);
TermPtr PositionGoal(const Attachment& at, const Eigen::Vector3d& target_W);
/// Orientation with per-axis weights: w_i (R e_i − R_target e_i), i = x, y, z (9 rows; a zero
/// weight frees rotation that moves that axis only through the others).
class OrientationGoalTerm final : public Term {
 public:
  /// @throws std::invalid_argument when R_target is not a rotation.
  OrientationGoalTerm(int body, const Eigen::Matrix3d& R_target, const Eigen::Vector3d& weights);
  /// Moves the target (each servo tick of a 6-DOF device: the stylus). @pre a rotation.
  void set_target(const Eigen::Matrix3d& R_target);
  const Eigen::Matrix3d& target() const { return R_; }
  std::string name() const override { return "orientation_goal"; }
  int dim() const override { return 9; }
  int body_a() const override { return body_; }
  void Evaluate(const std::vector<BodyPose>& poses, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override;
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override;

 private:
  int body_;
  Eigen::Matrix3d R_;
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

}  // namespace tangent::optimizer
