#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "optimizer/evaluator.h"
#include "optimizer/joints.h"
#include "optimizer/problem.h"

namespace tangent::optimizer {

enum class DexterityMeasure { kDexterity, kInverseCondition, kForceTransmission };

/// Kinematic performance of an end-effector point with respect to chosen revolute joints, for
/// serial chains and closed loops alike (seed 001 Eq. 1, §6).
///
/// In maximal coordinates the mechanism's velocities satisfy C q̇ = 0 (the problem's equality
/// rows: joints, unit quaternions, closures) and the chosen joints' rates are θ̇ = A q̇ (A the
/// gradients of their angles). When the chosen joints are as many as the mechanism's degrees of
/// freedom, B = [C; A] is square and regular, the motion is q̇ = B⁻¹[0; θ̇], and the end effector's
/// velocity ẋ = X q̇ gives the mechanism Jacobian
///     J = X S,   S = B⁻¹[0; I]   (3 x m)
/// (J through the null space of C: S spans it, normalized so that A S = I). Measures of J:
///   dexterity               w = √det(J Jᵀ) (m ≥ 3) or √det(Jᵀ J) (m < 3: the product of the
///                           singular values either way),
///   inverse condition       σ_min/σ_max,
///   force transmission      1/σ_max: the least end-effector force per unit joint effort.
/// Gradients are analytic: with G = ∂f/∂J (from the SVD),
///   ∂f/∂q_k = ⟨G Sᵀ, ∂X/∂q_k⟩ − ⟨B⁻ᵀ Xᵀ G Sᵀ, ∂B/∂q_k⟩,
/// and a contraction ⟨Y, ∂R/∂q_k⟩ of stacked term rows R is column k of Σ_j H(Y_{:,j}) e_j, the
/// terms' weighted Hessians (Term::AddWeightedHessian) — n of them per gradient. For design
/// studies, not for the servo loop: evaluation allocates.
///
/// Each thread keeps the last few points it evaluated (the evaluators there, B's factorization,
/// S and the SVD of J), so that a gradient asked at a point whose value was just asked (a line
/// search's accepted step, then the next iteration's gradient) does not factor B again. The
/// measures are a pure function of q (every point is evaluated by fresh evaluators, no warm
/// start carries over), so a point found there gives the same bits as evaluating it again:
/// results do not depend on what a thread evaluated before.
class Dexterity {
 public:
  struct Measures {
    Eigen::MatrixXd J;  ///< 3 x m mechanism Jacobian
    double dexterity = 0.0, inverse_condition = 0.0, force_transmission = 0.0;
    Eigen::VectorXd grad_dexterity, grad_inverse_condition, grad_force_transmission;
  };
  /// `problem`: its equalities define C (it must outlive this). `joints`: the chosen revolute
  /// joints as attachment pairs (as given to RevoluteJoint).
  /// @throws std::invalid_argument when no joint is chosen.
  Dexterity(const Problem& problem, const Attachment& end_effector,
            const std::vector<std::pair<Attachment, Attachment>>& joints);

  /// The measures at q (gradients when asked). @throws std::runtime_error when B is singular
  /// (the chosen joints do not parameterize the mechanism's motion there).
  Measures Evaluate(const Eigen::VectorXd& q, bool gradients) const;
  /// The measures with only the gradients whose GradientBit is set in `gradients` (each costs n
  /// weighted Hessian evaluations; the others are left empty).
  Measures Evaluate(const Eigen::VectorXd& q, int gradients) const;
  static constexpr int GradientBit(DexterityMeasure m) { return 1 << static_cast<int>(m); }
  static constexpr int kAllGradients = 7;

 private:
  struct Point;
  /// The evaluation at q without gradients: from this thread's recent points, else made there.
  const Point& At(const Eigen::VectorXd& q) const;

  std::uint64_t id_;  ///< names this instance in the threads' point caches (addresses recur)
  const Problem& problem_;
  Problem aux_;  ///< unit quaternions, then X (3 rows), then one angle row per chosen joint
  int x_row_ = 0, a_row_ = 0, m_ = 0;
};

std::shared_ptr<DesignObjective> MakeDexterityObjective(std::shared_ptr<const Dexterity> d,
                                                        DexterityMeasure measure);

}  // namespace tangent::optimizer
