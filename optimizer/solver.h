#pragma once

#include <memory>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include "optimizer/clearance_guard.h"
#include "optimizer/dense_cholesky.h"
#include "optimizer/evaluator.h"
#include "optimizer/problem.h"

namespace tangent::optimizer {

struct SolverOptions {
  int max_iterations = 60;  ///< Gauss–Newton steps (multiplier updates are not counted)
  /// Wall-clock budget per Solve in microseconds (0: none). The best iterate is returned.
  double time_budget_us = 0.0;
  double constraint_tolerance = 1e-10;  ///< max |c_E|, max(0, −c_I), in the terms' units
  double kkt_tolerance = 1e-8;          ///< |∇E − J_Eᵀλ_E − J_Iᵀλ_I|∞
  /// μ of the augmented Lagrangian: the weight of the constraints in the Newton matrix and the
  /// inverse of the regularization of the multiplier block. Large enough that the constraints
  /// dominate (joint rows are O(1)), small enough that μJᵀJ leaves the objective's digits.
  double penalty = 1e6;
  /// Levenberg–Marquardt damping added to the Newton matrix, relative to the largest diagonal
  /// entry of its objective part (least astonishment and objective terms).
  double damping = 1e-12;
  /// An indefinite Newton matrix's own step (Solver::IndefiniteStep) along an eigenvector whose
  /// eigenvalue is smaller in magnitude than this times the objective's scale (the largest
  /// diagonal entry of the objective part, as for `damping`) is damped to that floor: a motion
  /// that a loaded contact's curvature leaves nearly free, where least astonishment no longer
  /// holds the step to the tick (docs/optimizer.md, "Indefinite Newton matrices"). 0: damped only
  /// to the matrix's rounding (1e-12 of its largest eigenvalue).
  double indefinite_floor = 0.0;
  /// Linear algebra of the Newton step: dense LLᵀ for small systems, sparse LDLᵀ (Eigen's
  /// SimplicialLDLT, symbolic analysis done once per constraint structure) for large ones;
  /// kAuto picks sparse above `sparse_threshold` coordinates.
  /// Trust region per Newton step and body: |ΔQ| (≈ half the rotation angle in radians for a
  /// unit quaternion) and |Δp| in metres (0: no limit). Warm servo steps stay far below.
  double max_rotation_step = 0.2;
  double max_translation_step = 0.0;
  /// Step reach (docs/stability.md): a step is shortened so that no contact row's two bodies
  /// move their copies of its contact point relative to each other by more than the row's reach
  /// (Term::Reach: its gap plus a quarter of its relative radius of curvature), so that each
  /// tracked extremum is continued along the step and a step cannot carry one surface through
  /// another past the contact that holds them apart. Off by default: measured so far only on
  /// the paperclip soak (docs/reliability.md), where it does not yet hold the chain on its own.
  bool step_reach = false;
  /// Solve motion bound (m; 0: none): every Newton step is shortened so that no point of a body
  /// the clearance guard marks (ClearanceGuard::Bound; within the body's reach from its origin)
  /// ends farther than this from where it was at the solve's anchor (ClearanceGuard::Motion).
  /// Needs the clearance guard (set_clearance_guard). The bodies are marked once a solve, when
  /// it first steps (Solver::set_motion_marker); the servo marks those of contacts near a
  /// pitchfork of their distance (ServoOptions::max_part_speed). A step it cuts to nothing
  /// updates no multiplier (docs/optimizer.md, "Steps at the motion bound"). Bodies the guard
  /// marks for the return bound instead (ClearanceGuard::BoundReturn; the servo's parts held by
  /// a line) step freely, but an unconverged solve returns no iterate that carried them farther
  /// than this from the anchor: the best one within it, at worst the start.
  double max_solve_motion = 0.0;
  /// A step the motion bound shortens keeps its normal part whole (Solver::SplitBoundedStep):
  /// a solve standing at its bound still restores its constraints instead of stopping there
  /// (docs/optimizer.md, "Steps at the motion bound"). Off by default: on the paperclip soak it
  /// frees the solve the bound froze, and the chain is then lost (docs/reliability.md).
  bool bounded_normal_step = false;
  /// Newton steps per iteration while the inequalities' active set changes (its guess from the
  /// multipliers, then its corrections from the linearized constraints after the step).
  int max_active_set_passes = 4;
  /// The finishing correction: an iterate that is complementary and stationary to 1e-2 of the
  /// KKT tolerance (well inside Newton's quadratic range: at the tolerance itself a solve could
  /// stop a Newton step short, measured 2.6e-8 m from IPOPT's four-bar optimum), with the
  /// violation over its tolerance by at most `finish_violation` times, is
  /// first corrected towards feasibility with the last Newton step's factorization,
  /// Δq = −H⁻¹ μ (J_Eᵀc_E + J_Aᵀc_A) (a second-order correction: the step's own curvature
  /// residual), which costs a back substitution and an evaluation instead of a Newton matrix and
  /// its factorization. Kept only if it lowers the violation; the multipliers are not changed.
  /// 0: never.
  double finish_violation = 1e3;
  /// An unconverged solve's returned iterate, off its rows by more than their tolerance and at
  /// most `finish_violation` times it, moved onto them by the least motion
  /// (Solver::RestoreFeasibility; docs/optimizer.md, "Stopping").
  bool restore_feasibility = true;
  /// Compute the reduced-Hessian statistic after each solve (dense eigen-decomposition,
  /// allocates: for tests and design studies, not for the servo loop).
  bool second_order_check = false;
  enum class Linear { kAuto, kDense, kSparse };
  Linear linear = Linear::kAuto;
  int sparse_threshold = 84;  ///< coordinates (12 moving bodies)
  /// Offline design runs (tangent-opt, docs/offline.md), where a solve is taken to convergence
  /// from a cold start instead of a warm servo step:
  ///  - the design objectives (gradient only) get curvature from a damped BFGS model B of
  ///    −Σ w ∇²f, built from their gradients along the steps taken (Powell's damping keeps B
  ///    positive definite; the first step is scaled so that |Δq| ≈ first_step), added to the
  ///    Newton matrix (dense);
  ///  - convergence asks |KKT|∞ ≤ relative_kkt_tolerance · max(|∇E(q₀)|∞, |E(q₀)|, kkt_floor):
  ///    relative to the objective's own scale, so a small weight or a small objective is still
  ///    solved to its digits (the absolute kkt_tolerance is not used);
  ///  - a step is also halved while the Lagrangian E − λᵀc rises above its linear model's
  ///    Armijo line (the violation safeguard stays).
  /// Least astonishment is the Problem's: set it to 0 for a pure design solve.
  struct Design {
    bool enabled = false;
    double relative_kkt_tolerance = 1e-9;
    double kkt_floor = 1e-12;
    double first_step = 0.05;
  } design;
};

struct SolveStats {
  int iterations = 0;   ///< Newton iterations
  int corrections = 0;  ///< finishing corrections and feasibility restorations kept
  /// Newton steps taken on a matrix that is not positive definite (Solver::IndefiniteStep).
  int indefinite_steps = 0;
  double max_violation = 0.0;
  double kkt_residual = 0.0;
  /// Largest constraint value of an inequality row carrying a positive multiplier (a force on
  /// a separated contact); converged solves have it within constraint_tolerance.
  double complementarity = 0.0;
  double objective = 0.0;
  double penalty = 1e6;
  bool converged = false;
  bool budget_exhausted = false;
  /// The input was not finite (a coordinate, or a goal target / term at the start point): no
  /// step was taken, q and the multipliers are as they came, the residuals are +inf.
  bool invalid_input = false;
  /// The motion marker marked bodies for this solve's steps (Solver::set_motion_marker), and
  /// the Newton steps the solve motion bound shortened (SolverOptions::max_solve_motion).
  bool motion_marked = false;
  int motion_bounded_steps = 0;
  /// The motion bound or the clearance guard left no fraction of a Newton step: the solve
  /// stopped, unconverged, where it stood (as it would after every later iteration).
  bool stopped_at_bound = false;
  /// Second-order check (only with SolverOptions::second_order_check): the Lagrangian's Hessian
  /// restricted to the null space of the active constraints' Jacobian is positive definite
  /// (a strict local minimum, not a saddle), and its smallest eigenvalue.
  bool reduced_hessian_checked = false;
  bool reduced_hessian_positive_definite = false;
  double reduced_hessian_min_eigenvalue = 0.0;
};

/// One iteration of a solve, for convergence histories (offline: Solver::set_history).
struct IterationRecord {
  int iteration = 0;
  double objective = 0.0;  ///< E at the iterate
  double violation = 0.0;
  double kkt = 0.0;
};

/// Augmented Lagrangian with the PHR form for inequalities (design.md §4.5), in its primal-dual
/// (stabilized SQP) form: each iteration is a Newton step on the KKT conditions
///   ∇E − J_Eᵀλ_E − J_Iᵀλ_I = 0,   c_E + (λ_E − λ̄_E)/μ = 0,   and the PHR-shifted inequalities,
/// with λ̄ the current multipliers. Eliminating the multiplier step leaves the dense n x n system
///   (∇²E − Σλ_i∇²c_i + μ J_EᵀJ_E + μ J_AᵀJ_A) Δq = −(∇E − J_Eᵀ(λ_E − μc_E) − J_Iᵀ max(0, λ_I −
///   μc_I))
/// (LDLᵀ; A the active inequality rows), then λ ← λ − μ(c + JΔq) from the linearized constraints.
/// The active set is the step's own: guessed from λ − μc > 0, then corrected from the linearized
/// constraints, λ − μ(c + JΔq) > 0, and the step recomputed until they agree (primal-dual active
/// set). Converged means feasible, stationary and complementary (no multiplier on a row with
/// c > tolerance). The curvature is exact where terms provide second derivatives
/// (Term::AddWeightedHessian), Gauss–Newton otherwise; Levenberg damping makes the matrix positive
/// definite where it is not; a step is halved while it would raise the violation tenfold.
/// Near a warm start this is Newton's method on the KKT system (quadratic convergence), and the
/// 1/μ block keeps redundant constraints regular. Quaternions are renormalized after each step
/// (the geometry ignores |Q|). Multipliers persist between Solve calls (warm start). All storage
/// is sized at construction: Solve allocates nothing.
class Solver {
 public:
  explicit Solver(const Problem& problem, const SolverOptions& options = {});
  /// Solves from *q (the previous tick's solution, also least astonishment's q_prev).
  SolveStats Solve(Eigen::VectorXd* q);
  /// The same problem, least astonishment measured from `anchor` (the previous solution), the
  /// iterations started from *q: e.g. a prediction along the path the solutions follow. The
  /// solution is the same as Solve from `anchor` (within the tolerances); only the way there
  /// differs.
  SolveStats Solve(Eigen::VectorXd* q, const Eigen::VectorXd& anchor);
  /// Forgets multipliers and penalty (after the constraint set or the goals jump).
  void Reset();
  const SolverOptions& options() const { return options_; }
  /// Changes the options for the next solves (e.g. a longer budget to settle a scene).
  void set_options(const SolverOptions& options) { options_ = options; }
  const Eigen::VectorXd& equality_multipliers() const { return lambda_e_; }
  const Eigen::VectorXd& inequality_multipliers() const { return lambda_i_; }
  /// Restores multipliers (e.g. with a saved configuration, after a failed attempt).
  void set_multipliers(const Eigen::VectorXd& equality, const Eigen::VectorXd& inequality) {
    lambda_e_ = equality;
    lambda_i_ = inequality;
  }
  bool sparse() const { return H_.is_sparse(); }
  /// Appends one record per iteration to *history (nullptr: none). Offline only: it evaluates
  /// the objective each iteration and allocates.
  void set_history(std::vector<IterationRecord>* history) { history_ = history; }
  /// Shortens every step to what `guard` admits (optimizer/clearance_guard.h; nullptr: none).
  /// The guard must outlive the solver's solves.
  void set_clearance_guard(const ClearanceGuard* guard) { guard_ = guard; }
  /// SolverOptions::max_solve_motion for the next solves (the servo's, each tick).
  void set_max_solve_motion(double bound) { options_.max_solve_motion = bound; }
  /// Marks the clearance guard's bodies for the motion bound (ClearanceGuard::Bound) and says
  /// whether any is marked. Called at most once a solve, just before its first step is bounded,
  /// with the solve's start evaluated: a solve that takes no step (most of a servo's) pays
  /// nothing for it. Allocation free as the marker is. nullptr: the marks as they stand.
  using MotionMarker = bool (*)(void* context);
  void set_motion_marker(MotionMarker marker, void* context) {
    motion_marker_ = marker;
    motion_context_ = context;
  }
  /// This solver's per-solve data of the problem: goal targets, tracked contacts (the Problem
  /// is shared and never changed; several solvers of one problem may run on different threads).
  ProblemData& data() { return ev_.data(); }
  const ProblemData& data() const { return ev_.data(); }

 private:
  void AugmentedGradient();
  /// Restores q and the multipliers to the solve's start and marks the stats invalid_input.
  SolveStats InvalidInput(Eigen::VectorXd* q, SolveStats st);
  /// Builds H_; returns the scale of its objective part (for the damping).
  double NewtonMatrix();
  /// H_ += μ J_EᵀJ_E + μ J_AᵀJ_A (A: the active inequality rows, active_).
  void AddRowsGaussNewton();
  double Violation() const;
  double Complementarity() const;
  void Normalize(Eigen::VectorXd* q) const;

  /// Assembles and factorizes the Newton matrix for the current active set and solves for step_
  /// (an indefinite matrix's own step when that is within the trust region, IndefiniteStep;
  /// else damped until positive definite and within it); @return the damping used.
  double NewtonStep();
  bool Factorize();
  /// The Newton step of H_ (after the base damping) when it is not positive definite, from its
  /// eigendecomposition: exact along every eigenvector whose eigenvalue is above 1e-12 of the
  /// largest in magnitude, negative ones included; damped to that floor along the others (the
  /// directions the matrix does not determine at double precision). true with step_ set.
  bool IndefiniteStep(double objective_scale);
  void SolveStep();
  void SecondOrderCheck(const Eigen::VectorXd& q, SolveStats* st);
  /// An orthonormal basis (n x k, k ≥ 0) of the motions the active constraints leave free at the
  /// last Evaluate (offline: dense, allocates).
  Eigen::MatrixXd FreeMotions() const;
  /// The constraints' Jacobian at the last Evaluate, dense: equality rows, then inequality rows
  /// (offline: allocates).
  Eigen::MatrixXd DenseConstraintJacobian() const;
  /// The same into *J, through the per-kind blocks *part_e and *part_i (allocation free once
  /// they have their shapes).
  void FillConstraintJacobian(Eigen::MatrixXd* J, Eigen::MatrixXd* part_e,
                              Eigen::MatrixXd* part_i) const;
  /// ∇E − J_Eᵀλ_E − J_Iᵀλ_I at the last Evaluate and the current multipliers.
  void KktResidual(Eigen::VectorXd* r) const;
  /// Multipliers for the rows that have none yet: the equalities with λ = 0 and the
  /// inequalities at their bound (c ≤ tolerance) with λ = 0 get the values that best balance ∇E
  /// at q with the other rows' multipliers held (least squares; an inequality that comes out
  /// pulling is dropped). A design solve's cold start, and a servo solve whose contacts touch
  /// unloaded. Allocation free. need_inequality: only if an inequality row is among them.
  /// @return whether any row was estimated.
  bool LeastSquaresMultipliers(bool need_inequality);
  bool StepWithinTrustRegion() const;
  /// A Newton step the solve motion bound shortens, split into its normal part, which cancels
  /// the linearized constraints, −H⁻¹ μ (J_Eᵀc_E + J_Aᵀc_A) (step_normal_), and the rest
  /// (step_, the motion along them): the normal part is taken whole and the bound shortens only
  /// the rest, so a solve standing at its bound still restores feasibility rather than stopping
  /// (docs/optimizer.md, "Steps at the motion bound"). Sets q_base_ = q + step_normal_ (normalized)
  /// and the Jacobian products of both parts. false (nothing changed) when the normal part does not
  /// itself fit within the bound and the clearance guard's share.
  bool SplitBoundedStep(const Eigen::VectorXd& q);
  /// SolverOptions::finish_violation's correction of *q (ev_, grad_e_ and kkt_ at *q, st's
  /// residuals its own). Kept (q, ev_, grad_e_, kkt_ and st at the corrected point) only if it
  /// lowers the violation with finite residuals; otherwise all are as they came.
  void FinishingCorrection(Eigen::VectorXd* q, SolveStats* st);
  /// An unconverged solve's returned iterate *q (ev_ at it, st's violation its own) moved onto
  /// its equality rows and the inequality rows violated or loaded there by the least motion:
  /// up to two Gauss–Newton steps on those rows alone, each kept only if it lowers the violation
  /// within the clearance guard and the return bound. ev_, grad_e_, kkt_ and st's residuals at
  /// the *q it leaves.
  void RestoreFeasibility(Eigen::VectorXd* q, SolveStats* st);
  /// Design mode: the BFGS update of B_ with the step from q_old_ to q and the change of the
  /// design gradient (gd_ − gd_old_).
  void UpdateDesignCurvature(const Eigen::VectorXd& q);
  /// Design mode after a stall: B_ = Z (Zᵀ H Z) Zᵀ, Z the active constraints' free motions, H Z
  /// by forward differences of the design gradient at q.
  void DesignCurvatureByDifferences(const Eigen::VectorXd& q);
  /// The Lagrangian E − λ_Eᵀc_E − λ_Iᵀc_I at the last Evaluate (design mode's line search).
  double Lagrangian(const Eigen::VectorXd& q);
  /// E(q), remembered for the last q it was computed at (within a solve): the line search's
  /// accepted point is the next iterate, whose objective the history, the tolerance and the
  /// next line search all ask for again (a design objective's value costs a factorization).
  double ObjectiveAt(const Eigen::VectorXd& q);

  const Problem& problem_;
  SolverOptions options_;
  const ClearanceGuard* guard_ = nullptr;
  /// Whether an unconverged solve may return q: every body the guard marks for it
  /// (ClearanceGuard::BoundReturn) within the motion bound of the solve's anchor.
  bool Returnable(const Eigen::VectorXd& q) const {
    return !guard_ || !(options_.max_solve_motion > 0.0) ||
           guard_->ReturnWithin(q_prev_, q, options_.max_solve_motion);
  }
  MotionMarker motion_marker_ = nullptr;
  void* motion_context_ = nullptr;
  int n_ = 0;
  ProblemEvaluator ev_;
  BlockMatrix H_;
  std::vector<Matrix7d> M_;
  Eigen::VectorXd q_prev_, lambda_e_, lambda_i_, g_, step_, q_try_, q_best_, shifted_;
  Eigen::VectorXd objective_q_;  ///< where objective_value_ was computed (ObjectiveAt)
  double objective_value_ = 0.0;
  bool objective_known_ = false;
  // The solve's start and its best iterate's multipliers (undo a non-finite solve).
  Eigen::VectorXd q_start_, lambda_e_start_, lambda_i_start_, lambda_e_best_, lambda_i_best_;
  Eigen::VectorXd weights_, gn_e_, gn_i_, gn_o_, kkt_, grad_e_, linearized_e_, linearized_i_,
      jstep_e_, jstep_i_;
  // A motion-bounded step's parts (SplitBoundedStep): the normal step and its Jacobian products.
  Eigen::VectorXd step_normal_, q_base_, jnormal_e_, jnormal_i_;
  // Dense Newton matrices up to kSmallDense: DenseCholesky (the servo's). Larger ones (design
  // solves, 154 x 154 for the four-bar) keep Eigen's blocked LLT, whose matrix products pay
  // off there.
  static constexpr int kSmallDense = 64;
  DenseCholesky small_llt_;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt_;
  // Natural ordering on the upper triangle: factorize() then reads the matrix in place (with a
  // fill-reducing ordering or the lower triangle it builds a permuted copy: 4 allocations per
  // factorization, measured). Bodies are numbered along their chains, which keeps fill low.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      ldlt_;
  std::vector<char> active_;  ///< inequality rows in the current step's active set
  // LeastSquaresMultipliers' storage (all rows: equalities, then inequalities).
  Eigen::MatrixXd ls_J_, ls_part_e_, ls_part_i_, ls_G_, ls_JJt_;
  Eigen::VectorXd ls_r_, ls_Jr_, ls_rhs_, ls_lambda_;
  Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> ls_ldlt_;
  std::vector<char> ls_unknown_;
  // The Newton step of a matrix that is not positive definite (IndefiniteStep; servo-sized
  // dense matrices only): its eigendecomposition, in storage of a fixed largest size so that
  // neither it nor its solves allocate.
  using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                    kSmallDense, kSmallDense>;
  using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kSmallDense, 1>;
  SmallMatrix kkt_full_;
  Eigen::SelfAdjointEigenSolver<SmallMatrix> kkt_eig_;
  SmallVector kkt_inverse_, kkt_y_;
  int indefinite_steps_ = 0;  ///< this solve's (SolveStats::indefinite_steps)
  bool indefinite_ = false;   ///< SolveStep uses kkt_eig_ (IndefiniteStep), not a Cholesky factor
  double mu_ = 0.0;
  bool factor_ok_ = false;       ///< the last Newton step left a usable factorization
  bool kept_jacobians_ = false;  ///< ev_ kept the last step's Jacobians (finishing correction)
  // Design mode only (empty otherwise): the BFGS model of the design objectives' curvature, the
  // design gradient now and at the previous iterate, and that iterate.
  std::vector<IterationRecord>* history_ = nullptr;
  Eigen::MatrixXd B_;
  Eigen::VectorXd gd_, gd_old_, q_old_;
  bool have_old_ = false;
  bool bfgs_scaled_ = false;   ///< the first BFGS update has rescaled the initial model
  bool fd_curvature_ = false;  ///< after a stall: B by differences of the design gradient
  double stall_kkt_ = 0.0;     ///< the KKT residual at the last halving (stall detection)
  double last_step_ = 0.0;     ///< |Δq| of the last step taken
  int stall_iterations_ = 0;
};

}  // namespace tangent::optimizer
