#include "optimizer/solver.h"
#include "optimizer/step_reach.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <chrono>
#include <limits>

namespace tangent::optimizer {

namespace {

bool UseSparse(const SolverOptions& o, int n) {
  if (o.design.enabled) return false;  // B is dense
  switch (o.linear) {
    case SolverOptions::Linear::kDense:
      return false;
    case SolverOptions::Linear::kSparse:
      return true;
    case SolverOptions::Linear::kAuto:
      break;
  }
  return n > o.sparse_threshold;
}

// Every coordinate finite (a loop: Eigen's allFinite, (x − x) == (x − x), is an out-of-line call
// of ~30 instructions a coordinate here).
bool AllFinite(const Eigen::VectorXd& x) {
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) return false;
  }
  return true;
}

}  // namespace

Solver::Solver(const Problem& problem, const SolverOptions& options)
    : problem_(problem),
      options_(options),
      ev_(problem, /*dense_jacobians=*/false),
      H_(problem.mechanism().num_moving(), ev_.CoupledBlocks(),
         UseSparse(options, problem.mechanism().num_coordinates())) {
  const Mechanism& m = problem.mechanism();
  n_ = m.num_coordinates();
  M_.assign(static_cast<size_t>(m.num_moving()), Matrix7d::Zero());
  q_prev_.setZero(n_);
  g_.setZero(n_);
  step_.setZero(n_);
  q_try_.setZero(n_);
  objective_q_.setZero(n_);
  q_best_.setZero(n_);
  q_start_.setZero(n_);
  lambda_e_start_.setZero(problem.num_equality_rows());
  lambda_i_start_.setZero(problem.num_inequality_rows());
  lambda_e_best_.setZero(problem.num_equality_rows());
  lambda_i_best_.setZero(problem.num_inequality_rows());
  shifted_.setZero(problem.num_inequality_rows());
  active_.assign(static_cast<size_t>(problem.num_inequality_rows()), 0);
  {
    const int rows = problem.num_equality_rows() + problem.num_inequality_rows();
    ls_J_.setZero(rows, n_);
    ls_part_e_.setZero(problem.num_equality_rows(), n_);
    ls_part_i_.setZero(problem.num_inequality_rows(), n_);
    ls_G_.setZero(rows, rows);
    ls_JJt_.setZero(rows, rows);
    ls_r_.setZero(n_);
    ls_Jr_.setZero(rows);
    ls_rhs_.setZero(rows);
    ls_lambda_.setZero(rows);
    ls_ldlt_ = Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower>(rows);
    ls_unknown_.assign(static_cast<size_t>(rows), 0);
  }
  kkt_.setZero(n_);
  grad_e_.setZero(n_);
  linearized_e_.setZero(problem.num_equality_rows());
  linearized_i_.setZero(problem.num_inequality_rows());
  jstep_e_.setZero(problem.num_equality_rows());
  jstep_i_.setZero(problem.num_inequality_rows());
  step_normal_.setZero(n_);
  q_base_.setZero(n_);
  jnormal_e_.setZero(problem.num_equality_rows());
  jnormal_i_.setZero(problem.num_inequality_rows());
  weights_.setZero(std::max({problem.num_equality_rows(), problem.num_inequality_rows(),
                             problem.num_objective_rows(), 1}));
  gn_e_.setZero(problem.num_equality_rows());
  gn_i_.setZero(problem.num_inequality_rows());
  gn_o_.setZero(problem.num_objective_rows());
  for (const Problem::Entry& o : problem.objectives()) {
    gn_o_.segment(o.row, o.term->dim()).setConstant(o.weight);
  }
  if (options.design.enabled) {
    B_.setZero(n_, n_);
    gd_.setZero(n_);
    gd_old_.setZero(n_);
    q_old_.setZero(n_);
  }
  if (H_.is_sparse()) {
    ldlt_.analyzePattern(H_.sparse());  // The structure is fixed: analysed once.
  } else if (n_ <= kSmallDense) {
    small_llt_.Reserve(n_);
    kkt_full_.setZero(n_, n_);
    kkt_inverse_.setZero(n_);
    kkt_y_.setZero(n_);
  } else if (!options.design.enabled) {
    // Sizes the factorization's storage (later computes reuse it: the servo's solves allocate
    // nothing). Not LLT(n_) assigned: that constructor leaves its status uninitialized and the
    // move copies it (UBSan: "not a valid value for type ComputationInfo"). Design solves
    // allocate anyway, and there this n³/3 factorization of the identity was 4 % of a four-bar
    // solve's instructions.
    llt_.compute(Eigen::MatrixXd::Identity(n_, n_));
  }
  Reset();
}

void Solver::Reset() {
  lambda_e_.setZero(problem_.num_equality_rows());
  lambda_i_.setZero(problem_.num_inequality_rows());
  mu_ = options_.penalty;
  if (B_.size()) B_.setZero();
  have_old_ = false;
  bfgs_scaled_ = false;
  fd_curvature_ = false;
  last_step_ = 0.0;
}

void Solver::UpdateDesignCurvature(const Eigen::VectorXd& q) {
  if (have_old_) {
    // Damped BFGS (Powell): s the step, y the change of the design gradient; when sᵀy is small
    // against sᵀBs (the model's curvature, or a direction of negative curvature), y is blended
    // with Bs so that B stays positive definite.
    const Eigen::VectorXd s = q - q_old_;
    const Eigen::VectorXd y = gd_ - gd_old_;
    const double ss = s.squaredNorm(), sy = s.dot(y);
    if (ss > 0.0 && std::isfinite(sy)) {
      if (!bfgs_scaled_) {
        // The first update replaces the first step's guess by a multiple of the identity with
        // the curvature seen along s (Nocedal & Wright's scaling). (It used to test B for zero,
        // which the first step's guess never is: the guess, g/0.05, stayed and kept the steps
        // short — the adjustable-link finger crept for 55 iterations at full-length steps.)
        const double yy = y.squaredNorm();
        const double b = sy > 0.0 ? yy / sy : std::sqrt(yy / ss);
        if (b > 0.0 && std::isfinite(b)) {
          B_.setZero();
          B_.diagonal().setConstant(b);
        }
        bfgs_scaled_ = true;
      }
      const Eigen::VectorXd Bs = B_ * s;
      const double sBs = s.dot(Bs);
      const double theta = sy >= 0.2 * sBs ? 1.0 : 0.8 * sBs / (sBs - sy);
      const Eigen::VectorXd r = theta * y + (1.0 - theta) * Bs;
      const double sr = s.dot(r);
      if (sBs > 0.0 && sr > 0.0) {
        B_.noalias() -= (1.0 / sBs) * Bs * Bs.transpose();
        B_.noalias() += (1.0 / sr) * r * r.transpose();
      }
    }
  } else if (B_.isZero(0.0)) {
    // Before any step: a scaled identity that makes the first step about first_step long.
    const double g = gd_.norm();
    if (g > 0.0) B_.diagonal().setConstant(g / options_.design.first_step);
  }
  q_old_ = q;
  gd_old_ = gd_;
  have_old_ = true;
}

[[gnu::always_inline]] inline void Solver::KktResidual(Eigen::VectorXd* r) const {
  *r = grad_e_;
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kEquality, lambda_e_, -1.0, r);
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kInequality, lambda_i_, -1.0, r);
}

void Solver::FillConstraintJacobian(Eigen::MatrixXd* J, Eigen::MatrixXd* part_e,
                                    Eigen::MatrixXd* part_i) const {
  // Assembled from the terms' blocks (it used to be column by column from Jacobian products:
  // n passes over every term).
  ev_.DenseJacobian(ProblemEvaluator::kEquality, part_e);
  ev_.DenseJacobian(ProblemEvaluator::kInequality, part_i);
  J->resize(part_e->rows() + part_i->rows(), n_);  // (no allocation when already this shape)
  J->topRows(part_e->rows()) = *part_e;
  J->bottomRows(part_i->rows()) = *part_i;
}

Eigen::MatrixXd Solver::DenseConstraintJacobian() const {
  Eigen::MatrixXd J, part_e, part_i;
  FillConstraintJacobian(&J, &part_e, &part_i);
  return J;
}

bool Solver::LeastSquaresMultipliers(bool need_inequality) {
  // min |r − J_Uᵀλ_U|² over the unknown rows U (the equalities with λ = 0, the inequalities
  // within the constraint tolerance of their bound with λ = 0), r = ∇E − Jᵀλ the residual the
  // other rows leave, by the normal equations J_U J_Uᵀ λ_U = J_U r with a relative 1e-12 on the
  // diagonal: redundant rows get a regularized, near minimum-norm share. The system keeps its
  // full size (a row outside U is an identity row with right-hand side 0), so nothing is
  // allocated. An inequality that comes out pulling (λ < 0) is not held by its bound: dropped,
  // and solved again. (A start only: the solve refines the multipliers. Measured: a design start
  // at the optimum, on a length bound, took 28 iterations from λ = 0 while the bound's
  // multiplier built up through the penalty; and a servo solve from the paperclip chain at rest,
  // its hooks touching unloaded, took a first Newton step of |Δq| = 0.15 with no contact
  // curvature in the matrix — a hook turned 17°, 4 mm into the other wire — where the estimate
  // gives 7e-3 and 3 iterations.)
  const int me = ev_.c_e().size(), mi = ev_.c_i().size(), m = me + mi;
  bool any_inequality = false, any = false;
  for (int i = 0; i < m; ++i) {
    const bool unknown =
        i < me ? lambda_e_[i] == 0.0
               : lambda_i_[i - me] == 0.0 && ev_.c_i()[i - me] <= options_.constraint_tolerance;
    ls_unknown_[static_cast<size_t>(i)] = unknown;
    any = any || unknown;
    any_inequality = any_inequality || (unknown && i >= me);
  }
  if (!any || (need_inequality && !any_inequality)) return false;
  FillConstraintJacobian(&ls_J_, &ls_part_e_, &ls_part_i_);
  KktResidual(&ls_r_);
  ls_G_.setZero();
  ls_G_.selfadjointView<Eigen::Lower>().rankUpdate(ls_J_);
  ls_Jr_.noalias() = ls_J_ * ls_r_;
  for (int round = 0; round <= mi; ++round) {
    double scale = 0.0;
    for (int i = 0; i < m; ++i) {
      if (ls_unknown_[static_cast<size_t>(i)]) scale = std::max(scale, ls_G_(i, i));
    }
    for (int j = 0; j < m; ++j) {
      const bool uj = ls_unknown_[static_cast<size_t>(j)];
      for (int i = j; i < m; ++i) {
        const bool ui = ls_unknown_[static_cast<size_t>(i)];
        ls_JJt_(i, j) = ui && uj ? ls_G_(i, j) : (i == j ? 1.0 : 0.0);
      }
      if (uj) ls_JJt_(j, j) += 1e-12 * scale + 1e-300;
      ls_rhs_[j] = uj ? ls_Jr_[j] : 0.0;
    }
    ls_ldlt_.compute(ls_JJt_);
    ls_lambda_.noalias() = ls_ldlt_.solve(ls_rhs_);
    if (!ls_lambda_.allFinite()) return false;
    bool dropped = false;
    for (int i = me; i < m; ++i) {
      if (ls_unknown_[static_cast<size_t>(i)] && ls_lambda_[i] < 0.0) {
        ls_unknown_[static_cast<size_t>(i)] = 0;
        dropped = true;
      }
    }
    if (!dropped) break;
  }
  for (int i = 0; i < m; ++i) {
    if (!ls_unknown_[static_cast<size_t>(i)]) continue;
    if (i < me) {
      lambda_e_[i] = ls_lambda_[i];
    } else {
      lambda_i_[i - me] = std::max(0.0, ls_lambda_[i]);
    }
  }
  return true;
}

Eigen::MatrixXd Solver::FreeMotions() const {
  // The active constraints (equalities, inequalities with a positive multiplier) at the last
  // Evaluate, their Jacobian; an orthonormal basis of its null space.
  const int me = ev_.c_e().size(), mi = ev_.c_i().size();
  Eigen::MatrixXd J = DenseConstraintJacobian();
  int rows = me;
  for (int i = 0; i < mi; ++i) {
    if (lambda_i_[i] > 0.0) J.row(rows++) = J.row(me + i);
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(J.topRows(rows));
  lu.setThreshold(1e-10);
  if (lu.rank() == n_) return Eigen::MatrixXd(n_, 0);
  const Eigen::MatrixXd kernel = lu.kernel();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(kernel);
  return qr.householderQ() * Eigen::MatrixXd::Identity(n_, kernel.cols());
}

void Solver::DesignCurvatureByDifferences(const Eigen::VectorXd& q) {
  // Only the curvature along the motions the active constraints leave free matters (across
  // them μJᵀJ dominates the Newton matrix): with Z an orthonormal basis of the null space of
  // the equalities' and active inequalities' Jacobian, B = Z (Zᵀ H Z) Zᵀ, H Z by forward
  // differences of the analytic design gradient (gd_ holds it at q) along Z's columns — as
  // many gradients as free motions (2 for the adjustable-link finger, not its 28
  // coordinates). Steps of 1e-7: the gradient's own relative error is ~1e-12 here, so the
  // difference keeps ~5 digits, enough for Newton's superlinear convergence.
  const Eigen::MatrixXd Z = FreeMotions();
  B_.setZero();
  if (Z.cols() == 0) return;
  const double h = 1e-7 * std::max(1.0, q.cwiseAbs().maxCoeff());
  Eigen::MatrixXd HZ(n_, Z.cols());
  Eigen::VectorXd g(n_), gk;
  for (int c = 0; c < Z.cols(); ++c) {
    g.setZero();
    for (const Problem::DesignEntry& d : problem_.design_objectives()) {
      d.f->Gradient(q + h * Z.col(c), &gk);
      g -= d.weight * gk;
    }
    HZ.col(c) = (g - gd_) / h;
  }
  Eigen::MatrixXd reduced = Z.transpose() * HZ;
  reduced = (0.5 * (reduced + reduced.transpose())).eval();
  B_.noalias() = Z * reduced * Z.transpose();
}

double Solver::Lagrangian(const Eigen::VectorXd& q) {
  return ObjectiveAt(q) - lambda_e_.dot(ev_.c_e()) - lambda_i_.dot(ev_.c_i());
}

double Solver::ObjectiveAt(const Eigen::VectorXd& q) {
  if (objective_known_ && q.size() == objective_q_.size() &&
      std::equal(q.data(), q.data() + q.size(), objective_q_.data())) {
    return objective_value_;
  }
  objective_value_ = ev_.Objective(q, q_prev_, M_);
  objective_q_ = q;  // (sized at construction: no allocation)
  objective_known_ = true;
  return objective_value_;
}

void Solver::AugmentedGradient() {
  // g = ∇L = ∇E − J_Eᵀ(λ_E − μ c_E) − J_Aᵀ(λ_A − μ c_A), from the KKT residual
  // ∇E − J_Eᵀλ_E − J_Iᵀλ_I in kkt_: g = kkt + J_Eᵀ(μ c_E) + J_Iᵀ(λ_I − shifted), where an active
  // row's shifted multiplier is λ − μc (the row is an equality of this step) and an inactive
  // row's is 0.
  g_ = kkt_;
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kEquality, ev_.c_e(), mu_, &g_);
  for (int i = 0; i < ev_.c_i().size(); ++i) {
    shifted_[i] = active_[i] ? lambda_i_[i] - mu_ * ev_.c_i()[i] : 0.0;
    jstep_i_[i] = lambda_i_[i] - shifted_[i];  // (scratch)
  }
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kInequality, jstep_i_, 1.0, &g_);
}

void Solver::AddRowsGaussNewton() {
  gn_e_.setConstant(mu_);
  ev_.AddGaussNewton(ProblemEvaluator::kEquality, gn_e_, &H_);
  for (int i = 0; i < ev_.c_i().size(); ++i) gn_i_[i] = active_[i] ? mu_ : 0.0;
  ev_.AddGaussNewton(ProblemEvaluator::kInequality, gn_i_, &H_);
}

double Solver::NewtonMatrix() {
  // H = w_la M + Σ w J_oᵀJ_o + μ J_EᵀJ_E + μ J_AᵀJ_A (A: the active inequality rows), plus the
  // Lagrangian's curvature: objectives weighted by w r, equalities by −λ_E, active inequalities by
  // −λ_I. Assembled block by block.
  H_.SetZero();
  const double w_la = problem_.least_astonishment();
  for (size_t b = 0; b < M_.size(); ++b) {
    H_.Block(static_cast<int>(b), static_cast<int>(b)) = w_la * M_[b];
  }
  ev_.AddGaussNewton(ProblemEvaluator::kObjective, gn_o_, &H_);
  if (B_.size()) H_.AddDense(B_);  // design mode: the design objectives' curvature model
  // The objective's share of the matrix sets the damping's scale (1e-300: an empty objective).
  const double objective_scale = H_.MaxAbsDiagonal() + 1e-300;
  AddRowsGaussNewton();
  for (const Problem::Entry& o : problem_.objectives()) {
    weights_.segment(o.row, o.term->dim()) = o.weight * ev_.r_o().segment(o.row, o.term->dim());
  }
  ev_.AddCurvature(ProblemEvaluator::kObjective, weights_, &H_);
  weights_.head(ev_.c_e().size()) = -lambda_e_;
  ev_.AddCurvature(ProblemEvaluator::kEquality, weights_, &H_);
  for (int i = 0; i < ev_.c_i().size(); ++i) weights_[i] = active_[i] ? -lambda_i_[i] : 0.0;
  ev_.AddCurvature(ProblemEvaluator::kInequality, weights_, &H_);
  ev_.FoldRotations(&H_);
  return objective_scale;
}

bool Solver::Factorize() {
  indefinite_ = false;
  if (H_.is_sparse()) {
    ldlt_.factorize(H_.sparse());
    return ldlt_.info() == Eigen::Success && (ldlt_.vectorD().array() > 0.0).all();
  }
  if (n_ <= kSmallDense) return small_llt_.Compute(H_.dense());
  llt_.compute(H_.dense());
  return llt_.info() == Eigen::Success;
}

void Solver::SolveStep() {
  if (H_.is_sparse()) {
    step_ = ldlt_.solve(g_);
    step_ = -step_;
  } else if (indefinite_) {
    kkt_y_.noalias() = kkt_eig_.eigenvectors().transpose() * g_;
    kkt_y_.array() *= kkt_inverse_.array();
    step_.noalias() = -kkt_eig_.eigenvectors() * kkt_y_;
  } else {
    step_ = -g_;
    if (n_ <= kSmallDense) {
      small_llt_.SolveInPlace(&step_);
    } else {
      llt_.solveInPlace(step_);
    }
  }
}

bool Solver::StepWithinTrustRegion() const {
  if (!step_.allFinite()) return false;
  const double rot = options_.max_rotation_step, trans = options_.max_translation_step;
  for (int o = 0; o < n_; o += 7) {
    if (rot > 0.0 && step_.segment<4>(o + 3).norm() > rot) return false;
    if (trans > 0.0 && step_.segment<3>(o).norm() > trans) return false;
  }
  return true;
}

void Solver::SecondOrderCheck(const Eigen::VectorXd& q, SolveStats* st) {
  // H_L = ∇²E − Σ λ_i ∇²c_i: the Newton matrix without the μ JᵀJ terms (μ = 0 while building).
  ev_.Evaluate(q);
  ev_.ObjectiveGradient(q, q_prev_, M_, &grad_e_);
  kkt_ = grad_e_;
  for (int i = 0; i < ev_.c_i().size(); ++i) active_[i] = lambda_i_[i] > 0.0;
  AugmentedGradient();
  const double mu = mu_;
  mu_ = 0.0;
  NewtonMatrix();
  mu_ = mu;
  Eigen::MatrixXd H = H_.is_sparse() ? Eigen::MatrixXd(H_.sparse()) : H_.dense();
  H = Eigen::MatrixXd(H.selfadjointView<Eigen::Upper>());
  const Eigen::MatrixXd Q = FreeMotions();
  st->reduced_hessian_checked = true;
  if (Q.cols() == 0) {  // no free motion: trivially a minimum
    st->reduced_hessian_positive_definite = true;
    st->reduced_hessian_min_eigenvalue = 0.0;
    return;
  }
  // The reduced Hessian's spectrum over the free motions.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Q.transpose() * H * Q);
  st->reduced_hessian_min_eigenvalue = eig.eigenvalues().minCoeff();
  st->reduced_hessian_positive_definite =
      st->reduced_hessian_min_eigenvalue > 1e-12 * std::max(1.0, eig.eigenvalues().maxCoeff());
}

void Solver::Normalize(Eigen::VectorXd* q) const {
  const Mechanism& m = problem_.mechanism();
  for (int b = 0; b < m.num_bodies(); ++b) {
    if (m.offset(b) >= 0) q->segment<4>(m.offset(b) + 3).normalize();
  }
}

namespace {

// max that keeps a NaN (std::max and Eigen's default maxCoeff drop it unless it comes first: a
// NaN configuration then reported violation 0 and "converged").
double NanMax(double v, double x) {
  return std::isnan(v) || std::isnan(x) ? std::numeric_limits<double>::quiet_NaN() : std::max(v, x);
}

double MaxAbs(const Eigen::VectorXd& x) {
  return x.size() ? x.cwiseAbs().maxCoeff<Eigen::PropagateNaN>() : 0.0;
}

}  // namespace

double Solver::Complementarity() const {
  double v = 0.0;
  for (int i = 0; i < ev_.c_i().size(); ++i) {
    if (!(lambda_i_[i] <= 0.0)) v = NanMax(v, ev_.c_i()[i]);  // (a NaN multiplier counts)
  }
  return v;
}

double Solver::Violation() const {
  double v = MaxAbs(ev_.c_e());
  for (int i = 0; i < ev_.c_i().size(); ++i) v = NanMax(v, -ev_.c_i()[i]);
  return v;
}

double Solver::NewtonStep() {
  AugmentedGradient();
  const double objective_scale = NewtonMatrix();
  // Levenberg damping until positive definite (the Lagrangian's curvature may not be). Its
  // scale is the objective's part of the matrix, not μJᵀJ's: the curvature along a
  // mechanism's free motions is of the objective's size, and damping sized by μ|J|² (here
  // 1e6 larger) would shorten every Newton step (measured: half the step, 4.5 iterations
  // per warm solve instead of 3).
  //
  // The same damping is the trust region: a step that turns a body by more than
  // max_rotation_step (|ΔQ|) or moves it more than max_translation_step is recomputed with
  // ten times the damping (Levenberg–Marquardt). A barely positive definite matrix otherwise
  // gives an enormous step along its weakest direction (measured: a paperclip hanging on two
  // contacts, free to spin about the line through them, flipped 186° in one step).
  //
  // A matrix that is not positive definite, where a loaded contact's curvature outweighs the
  // objective's along a motion that keeps it touching, first gets its Newton step from its
  // eigendecomposition (IndefiniteStep), taken when it is within the trust region. The solve is
  // Newton on the KKT conditions, which needs a regular matrix, not a definite one, and the line
  // search below judges a step by the constraints it leaves, not by descent. Damped instead
  // until positive definite (10 against a base of 1e-12 on the paperclip soak's line contacts),
  // such steps were 1e-7 long while the KKT residual grew, and every tick stalled at the
  // iteration cap (docs/optimizer.md, "Indefinite Newton matrices").
  double lm = options_.damping * objective_scale;
  H_.AddToDiagonal(lm);
  for (int attempt = 0; attempt < 40; ++attempt) {
    factor_ok_ = Factorize();
    if (factor_ok_) {
      SolveStep();
      if (StepWithinTrustRegion()) break;
    } else if (attempt == 0 && IndefiniteStep(objective_scale)) {
      factor_ok_ = true;
      if (StepWithinTrustRegion()) {
        ++indefinite_steps_;
        break;
      }
      indefinite_ = factor_ok_ = false;
    }
    const double more = std::max(1e-8 * objective_scale, 10 * lm);
    H_.AddToDiagonal(more - lm);
    lm = more;
  }
  return lm;
}

bool Solver::IndefiniteStep(double objective_scale) {
  // Servo-sized dense matrices outside design mode (whose line search wants descent).
  if (H_.is_sparse() || n_ > kSmallDense || options_.design.enabled) return false;
  kkt_full_ = H_.dense().selfadjointView<Eigen::Upper>();
  kkt_eig_.compute(kkt_full_);
  if (kkt_eig_.info() != Eigen::Success) return false;
  const auto& ev = kkt_eig_.eigenvalues();
  // Eigenvalues within 1e-12 of the largest (in magnitude) are the matrix's rounding: along
  // their eigenvectors the step is damped to that floor rather than amplifying it. (A pivoted
  // LDLᵀ solve differs from this one by 1-3 % at the paperclips' condition numbers of 1e14; the
  // hooks hold with floors from 1e-16 to 1e-9 alike: docs/optimizer.md.) Optionally also those
  // below indefinite_floor of the objective's scale: a nearly free motion, where a residual of
  // 3.6e-8 along an eigenvalue of −3.6e-7 made a 7e-3 step from a converged tick on the
  // paperclip soak's line contacts and flung the clips apart (docs/reliability.md, "Soak").
  const double floor =
      std::max(1e-12 * ev.cwiseAbs().maxCoeff(), options_.indefinite_floor * objective_scale);
  if (!(floor > 0.0)) return false;
  for (int i = 0; i < n_; ++i) {
    kkt_inverse_[i] = 1.0 / (std::abs(ev[i]) < floor ? floor : ev[i]);
  }
  indefinite_ = true;
  SolveStep();
  if (step_.allFinite()) return true;
  indefinite_ = false;
  return false;
}

bool Solver::SplitBoundedStep(const Eigen::VectorXd& q) {
  // g_ = kkt + μ J_Eᵀc_E + μ J_Aᵀc_A (AugmentedGradient), so the step −H⁻¹g_ is the sum of
  // −H⁻¹kkt and the normal part below, with the same factorization.
  q_try_ = step_;  // (scratch: the whole step)
  g_.setZero();
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kEquality, ev_.c_e(), mu_, &g_);
  for (int i = 0; i < ev_.c_i().size(); ++i) jnormal_i_[i] = active_[i] ? ev_.c_i()[i] : 0.0;
  ev_.AddJacobianTransposeTimes(ProblemEvaluator::kInequality, jnormal_i_, mu_, &g_);
  SolveStep();
  step_normal_ = step_;
  step_ = q_try_;
  if (!AllFinite(step_normal_)) return false;
  if (guard_->armed() && guard_->Fraction(q, step_normal_) < 1.0) return false;
  if (guard_->MotionFraction(q_prev_, q, step_normal_, 1.0, options_.max_solve_motion) < 1.0) {
    return false;
  }
  step_ -= step_normal_;
  q_base_ = q + step_normal_;
  Normalize(&q_base_);
  ev_.JacobianTimes(ProblemEvaluator::kEquality, step_normal_, &jnormal_e_);
  ev_.JacobianTimes(ProblemEvaluator::kInequality, step_normal_, &jnormal_i_);
  return true;
}

void Solver::FinishingCorrection(Eigen::VectorXd* q, SolveStats* st) {
  // The right-hand side of a Newton step at a stationary point, −μ(J_Eᵀc_E + J_Aᵀc_A) (the
  // KKT part ∇E − Jᵀλ within its tolerance is left out), with the last step's matrix: for
  // μ|J|² far above the objective's curvature, H⁻¹μJᵀc is the least-norm step that cancels the
  // linearized constraints, and its error is the factor's staleness (one step old) times c.
  g_.setZero();
  ev_.AddKeptJacobianTransposeTimes(ProblemEvaluator::kEquality, ev_.c_e(), mu_, &g_);
  for (int i = 0; i < ev_.c_i().size(); ++i) jstep_i_[i] = active_[i] ? ev_.c_i()[i] : 0.0;
  ev_.AddKeptJacobianTransposeTimes(ProblemEvaluator::kInequality, jstep_i_, mu_, &g_);
  SolveStep();
  if (AllFinite(step_)) {
    q_try_ = *q + step_;
    Normalize(&q_try_);
    ev_.Evaluate(q_try_);
    const double violation = Violation();
    if (violation < st->max_violation) {
      ev_.ObjectiveGradient(q_try_, q_prev_, M_, &grad_e_);
      KktResidual(&kkt_);
      const double kkt = MaxAbs(kkt_);
      if (std::isfinite(kkt)) {
        *q = q_try_;
        st->max_violation = violation;
        st->kkt_residual = kkt;
        st->complementarity = Complementarity();
        ++st->corrections;
        return;
      }
    }
  }
  // Not kept: everything back at q.
  ev_.Evaluate(*q);
  ev_.ObjectiveGradient(*q, q_prev_, M_, &grad_e_);
  KktResidual(&kkt_);
}

void Solver::RestoreFeasibility(Eigen::VectorXd* q, SolveStats* st) {
  // Gauss–Newton on the rows alone, (w M + μ J_EᵀJ_E + μ J_AᵀJ_A) Δq = −μ (J_Eᵀc_E + J_Aᵀc_A),
  // A the rows violated or loaded at *q: for μ|J|² far above w (the least-astonishment metric
  // M's weight) the correction of least M-norm that cancels the linearized rows, with a matrix of
  // its own (positive definite: no curvature, nothing indefinite, nothing another iterate's).
  const double w_la = problem_.least_astonishment();
  for (int i = 0; i < ev_.c_i().size(); ++i) {
    const double c = ev_.c_i()[i];
    active_[i] = c < 0.0 || lambda_i_[i] - mu_ * c > 0.0;
  }
  ev_.AnchorStates(0);
  bool away = false;  // ev_ at a trial not kept
  for (int pass = 0; pass < 2 && st->max_violation > options_.constraint_tolerance; ++pass) {
    H_.SetZero();
    for (size_t b = 0; b < M_.size(); ++b) {
      H_.Block(static_cast<int>(b), static_cast<int>(b)) = (w_la > 0.0 ? w_la : 1.0) * M_[b];
    }
    // (The metric is singular along each quaternion's own direction: damped as a Newton step
    // is, relative to its scale, more until the matrix factors.)
    const double scale = H_.MaxAbsDiagonal() + 1e-300;
    AddRowsGaussNewton();
    ev_.FoldRotations(&H_);
    bool factored = false;
    for (double lm = std::max(options_.damping, 1e-12) * scale, added = 0.0;
         !factored && lm <= scale; lm *= 100.0) {
      H_.AddToDiagonal(lm - added);
      added = lm;
      factored = Factorize();
    }
    if (!factored) break;
    g_.setZero();
    ev_.AddJacobianTransposeTimes(ProblemEvaluator::kEquality, ev_.c_e(), mu_, &g_);
    for (int i = 0; i < ev_.c_i().size(); ++i) jstep_i_[i] = active_[i] ? ev_.c_i()[i] : 0.0;
    ev_.AddJacobianTransposeTimes(ProblemEvaluator::kInequality, jstep_i_, mu_, &g_);
    SolveStep();
    // (No farther than the clearance guard allows: a correction of nanometres.)
    if (!AllFinite(step_) || (guard_ && guard_->armed() && guard_->Fraction(*q, step_) < 1.0)) {
      break;
    }
    q_try_ = *q + step_;
    Normalize(&q_try_);
    ev_.Evaluate(q_try_);
    const double violation = Violation();
    if (!(violation < st->max_violation) || !Returnable(q_try_)) {
      away = true;
      break;
    }
    *q = q_try_;
    st->max_violation = violation;
    ++st->corrections;
    ev_.AnchorStates(0);
  }
  // Everything at *q (its contacts as they were there).
  if (away) {
    ev_.RewindStates(0);
    ev_.Evaluate(*q);
  }
  ev_.ObjectiveGradient(*q, q_prev_, M_, &grad_e_);
  KktResidual(&kkt_);
  st->kkt_residual = MaxAbs(kkt_);
  st->complementarity = Complementarity();
  factor_ok_ = false;  // (the factorization is this correction's, not a Newton step's)
}

SolveStats Solver::InvalidInput(Eigen::VectorXd* q, SolveStats st) {
  *q = q_start_;
  lambda_e_ = lambda_e_start_;
  lambda_i_ = lambda_i_start_;
  st.invalid_input = true;
  st.converged = false;
  st.iterations = 0;
  st.max_violation = st.kkt_residual = st.complementarity = st.objective =
      std::numeric_limits<double>::infinity();
  return st;
}

SolveStats Solver::Solve(Eigen::VectorXd* q_io) { return Solve(q_io, *q_io); }

SolveStats Solver::Solve(Eigen::VectorXd* q_io, const Eigen::VectorXd& anchor) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Eigen::VectorXd& q = *q_io;
  // Kept to undo a solve whose input or iterates turn out non-finite (all sized at
  // construction: these copies allocate nothing).
  q_start_ = q;
  lambda_e_start_ = lambda_e_;
  lambda_i_start_ = lambda_i_;
  factor_ok_ = kept_jacobians_ = false;
  if (!AllFinite(q) ||
      // (Solve(&q) passes q as its own anchor: checked already.)
      (&anchor != q_io && (anchor.size() != n_ || !AllFinite(anchor)))) {
    return InvalidInput(&q, SolveStats{});
  }
  q_prev_ = anchor;
  problem_.mechanism().MetricBlocks(q_prev_, &M_);
  objective_known_ = false;  // (E depends on q_prev_ through least astonishment)
  SolveStats st;
  indefinite_steps_ = 0;
  int marks = -1;  // the motion marker's answer, asked at the first bounded step (-1: not yet)
  ev_.Evaluate(q);
  // Primal-dual augmented Lagrangian (stabilized SQP): Newton on
  //   ∇E − J_Eᵀλ_E − J_Iᵀλ_I = 0,   c_E + (λ_E − λ̄_E)/μ = 0   (and PHR-shifted inequalities)
  // with the proximal centre λ̄ the current multipliers. Eliminating Δλ leaves
  //   (∇²E − Σ λ_i ∇²c_i + μ JᵀJ) Δq = −(∇E − Jᵀ(λ − μc)),   λ ← λ − μ (c + J Δq),
  // i.e. the augmented-Lagrangian Newton step with the multipliers updated every iteration
  // from the linearized constraints. Near a warm start this is Newton on the KKT system
  // (quadratic convergence); the 1/μ block keeps redundant constraints regular.
  double best_score = std::numeric_limits<double>::infinity(), best_violation = 0.0, best_kkt = 0.0;
  // The anchor slots (TermState::Anchor): the best iterate's contacts, and the line search's
  // (the other one).
  int best_slot = 1;
  bool best_pending = false;  // the best iterate is the current one, its contacts not yet anchored
  const bool design = options_.design.enabled;
  double kkt_tolerance = options_.kkt_tolerance;
  for (st.iterations = 0; st.iterations < options_.max_iterations; ++st.iterations) {
    // ∇E once per iteration: the KKT residual and the step's right-hand side both use it.
    ev_.ObjectiveGradient(q, q_prev_, M_, &grad_e_, design ? &gd_ : nullptr);
    if (design) {
      if (st.iterations == 0) {
        // The objective's scale: its gradient at the start, or its value where the start is
        // stationary.
        kkt_tolerance =
            options_.design.relative_kkt_tolerance *
            std::max({MaxAbs(grad_e_), std::abs(ObjectiveAt(q)), options_.design.kkt_floor});
        // (A feasible cold start only: away from the constraints the least-squares balance
        // says nothing about the multipliers at the solution — measured, the arm on a plane
        // from a start 9 cm off it was led to a pose of zero dexterity.)
        if (lambda_e_.isZero(0.0) && lambda_i_.isZero(0.0) && grad_e_.allFinite() &&
            Violation() <= 1e3 * options_.constraint_tolerance) {
          LeastSquaresMultipliers(/*need_inequality=*/false);
        }
      }
      if (grad_e_.allFinite()) UpdateDesignCurvature(q);
    }
    st.max_violation = Violation();
    KktResidual(&kkt_);
    st.kkt_residual = MaxAbs(kkt_);
    if (design) {
      // A stalled solve (the KKT residual not halved in 10 iterations): the BFGS model has
      // learned curvature that does not hold (steps shrink while the residual stays). From
      // then on the design curvature along the free motions is the forward difference of the
      // analytic design gradient, one gradient per free motion: Newton's method to the end.
      // (Measured: the finger with an adjustable link at its length bound stalled at KKT 8e-3
      // with steps of 1e-7 under BFGS, and a reset BFGS stalled again at 4e-6. From the start,
      // far from a solution, the exact but indefinite curvature led the arm on a plane to a
      // saddle of zero dexterity: hence only near one.)
      if (st.iterations == 0 || st.kkt_residual < 0.5 * stall_kkt_) {
        stall_kkt_ = st.kkt_residual;
        stall_iterations_ = 0;
      } else if (++stall_iterations_ >= 10 && st.max_violation <= 1e-6 && last_step_ < 1e-3) {
        // (Only near a solution — feasible and taking small steps: far from one, an exact but
        // indefinite curvature can lead Newton's method to a saddle.)
        fd_curvature_ = true;
        stall_kkt_ = st.kkt_residual;
        stall_iterations_ = 0;
      }
      if (fd_curvature_) DesignCurvatureByDifferences(q);
    }
    if (history_) {
      history_->push_back({st.iterations, ObjectiveAt(q), st.max_violation, st.kkt_residual});
    }
    if (!std::isfinite(st.max_violation) || !std::isfinite(st.kkt_residual)) {
      // At the start this is the input (a non-finite goal target, or a term that cannot be
      // evaluated there): a defined status, q and the multipliers as they came. Later it is a
      // step gone wrong: stop and return the best iterate (below).
      if (st.iterations == 0) return InvalidInput(&q, st);
      break;
    }
    // Converged: feasible, stationary, and complementary (no force on a separated contact).
    st.complementarity = Complementarity();
    if (!design && factor_ok_ && kept_jacobians_ && st.iterations > 0 &&
        st.max_violation > options_.constraint_tolerance &&
        st.max_violation <= options_.finish_violation * options_.constraint_tolerance &&
        st.kkt_residual <= 1e-2 * kkt_tolerance &&
        st.complementarity <= options_.constraint_tolerance) {
      FinishingCorrection(&q, &st);
    }
    if (st.max_violation <= options_.constraint_tolerance &&
        st.complementarity <= options_.constraint_tolerance && st.kkt_residual <= kkt_tolerance) {
      st.converged = true;
      break;
    }
    // The best iterate so far, by the worse of its two residuals relative to their tolerances:
    // what an unconverged solve returns.
    const double score =
        std::max(st.max_violation / options_.constraint_tolerance, st.kkt_residual / kkt_tolerance);
    if (score < best_score && Returnable(q)) {
      best_score = score;
      q_best_ = q;
      lambda_e_best_ = lambda_e_;
      lambda_i_best_ = lambda_i_;
      best_violation = st.max_violation;
      best_kkt = st.kkt_residual;
      best_pending = true;  // its contacts anchored by this iteration's line search (below)
    }
    if (options_.time_budget_us > 0 &&
        std::chrono::duration<double, std::micro>(Clock::now() - start).count() >
            options_.time_budget_us) {
      st.budget_exhausted = true;
      break;
    }
    // Contacts touching unloaded (c ≈ 0, λ = 0) at the start of a solve that must move: their
    // multipliers from the least-squares balance of ∇E, so the first Newton matrix has their
    // curvature (−λ∇²c). Without it a body hanging on such contacts has only least astonishment
    // against turning, and the first step turns it as far as the trust region allows (measured
    // on the paperclip chain pulled from rest: see LeastSquaresMultipliers).
    if (!design && st.iterations == 0 && grad_e_.allFinite() &&
        LeastSquaresMultipliers(/*need_inequality=*/true)) {
      KktResidual(&kkt_);
    }
    // The inequalities' active set is the step's own (a primal-dual active-set, i.e. semismooth
    // Newton, iteration on λ⁺ = max(0, λ − μ(c + JΔq))): guessed from the multipliers and the
    // constraints at q, then corrected from the linearized constraints after the step until the
    // step and its active set agree. The guess alone (PHR's λ − μc > 0) drops a loaded contact
    // whose second-order residual after the last step is positive (c ≈ 7e-7 m ≫ λ/μ ≈ 2e-10),
    // and the unconstrained step then runs through it (measured on the paperclip drag: ticks
    // cycling through the 10-iteration budget, 8 % of them).
    for (int i = 0; i < ev_.c_i().size(); ++i) {
      active_[i] = lambda_i_[i] - mu_ * ev_.c_i()[i] > 0.0;
    }
    for (int pass = 0; pass < options_.max_active_set_passes; ++pass) {
      NewtonStep();
      ev_.JacobianTimes(ProblemEvaluator::kInequality, step_, &jstep_i_);
      bool changed = false;
      for (int i = 0; i < ev_.c_i().size(); ++i) {
        const bool want = lambda_i_[i] - mu_ * (ev_.c_i()[i] + jstep_i_[i]) > 0.0;
        changed |= want != active_[i];
        active_[i] = want;
      }
      if (!changed) break;
    }
    // Safeguard for steps far from a solution: halve while the violation after the step exceeds
    // what a Newton step may leave, second order in the step (10 |Δq|², joint rows curve like
    // link lengths and |Q|² − 1 like 1), tenfold the current violation or 1e3 x the tolerance.
    // (A first-order test, measured: a warm 5e-3 step leaving 2.5e-5 was cut to 1/8, its
    // multipliers updated from the short step, and the solve took 5 iterations instead of 3.)
    ev_.JacobianTimes(ProblemEvaluator::kEquality, step_, &jstep_e_);
    ev_.JacobianTimes(ProblemEvaluator::kInequality, step_, &jstep_i_);  // (the last pass's step)
    linearized_e_ = ev_.c_e();  // c at the current point, before trial evaluations replace it
    linearized_i_ = ev_.c_i();
    const double step2 = step_.squaredNorm();
    // The finishing correction's Jacobians: those the matrix was built with. Only for a step
    // whose second-order residual (10 |Δq|², as below) may exceed the tolerance: after a shorter
    // one there is nothing for it to correct.
    kept_jacobians_ =
        options_.finish_violation > 0.0 && 10.0 * step2 > options_.constraint_tolerance;
    if (kept_jacobians_) ev_.KeepJacobians();
    // Design mode: the Lagrangian at q and its slope along the step (kkt_ is its gradient).
    const double lagrangian = design ? Lagrangian(q) : 0.0;
    const double slope = design ? kkt_.dot(step_) : 0.0;
    bool split = false;  // the motion bound's step, normal part whole (SplitBoundedStep)
    double alpha = options_.step_reach ? ReachFraction(problem_, data(), q, step_) : 1.0;
    if (guard_ && guard_->armed()) alpha = std::min(alpha, guard_->Fraction(q, step_));
    if (guard_ && options_.max_solve_motion > 0.0) {
      if (marks < 0) {
        marks = !motion_marker_ || motion_marker_(motion_context_);
        st.motion_marked = marks && motion_marker_;
      }
      const double unbounded = alpha;
      if (marks > 0) {
        alpha = guard_->MotionFraction(q_prev_, q, step_, alpha, options_.max_solve_motion);
      }
      if (alpha < unbounded) {
        ++st.motion_bounded_steps;
        if (options_.bounded_normal_step && !options_.step_reach && SplitBoundedStep(q)) {
          split = true;
          alpha = guard_->armed() ? guard_->Fraction(q_base_, step_) : 1.0;
          alpha = guard_->MotionFraction(q_prev_, q_base_, step_, alpha, options_.max_solve_motion);
        }
      }
    }
    if (split) {
      ev_.JacobianTimes(ProblemEvaluator::kEquality, step_, &jstep_e_);
      ev_.JacobianTimes(ProblemEvaluator::kInequality, step_, &jstep_i_);
    } else if (alpha == 0.0) {
      // No fraction of the step (the motion bound or the clearance guard): no trial to evaluate
      // (ev_ is at q) and no multiplier update, which at the same point would be λ − μc every
      // iteration: the multipliers ran away (+0.06 N an iteration on the paperclip soak's
      // 6e-8 m, the KKT residual with them, from 2.5e-3 to 0.59 over a tick). Nothing changes,
      // so every later iteration would be this one: the solve stops where it stands.
      st.stopped_at_bound = true;
      break;
    }
    // Trials start from q's contact states: a rejected trial's (a contact re-solved onto another
    // branch of its pair, far along a step the line search then halves) must not be where the
    // shorter one starts (measured on the paperclip soak: every halving of a 2 mm step re-solved
    // from the far side of the wire, 1.8 mm deep, and the last one was taken 0.16 mm deep).
    // (In the slot not holding the best iterate's; an iterate just scored best keeps its own.)
    const int anchored = 1 - best_slot;
    ev_.AnchorStates(anchored);
    if (best_pending) {
      best_slot = anchored;
      best_pending = false;
    }
    const Eigen::VectorXd& from = split ? q_base_ : q;
    for (int k = 0, trials = design ? 30 : 8; k < trials; ++k) {
      q_try_ = from + alpha * step_;
      Normalize(&q_try_);
      if (k > 0) ev_.RewindStates(anchored);
      ev_.Evaluate(q_try_);
      const double allowed = std::max({10.0 * st.max_violation, 1e3 * options_.constraint_tolerance,
                                       10.0 * alpha * alpha * step2});
      const bool sufficient =
          !design || slope >= 0.0 ||
          Lagrangian(q_try_) <= lagrangian + 1e-4 * alpha * slope + 1e-12 * std::abs(lagrangian);
      // (The last trial is taken whatever it leaves, with the fraction it was taken at.)
      // (A split step's normal part alone, α = 0, is its last trial.)
      if ((Violation() <= allowed && sufficient) || k + 1 == trials || alpha == 0.0) break;
      alpha *= 0.5;
    }
    last_step_ = alpha * std::sqrt(step2);
    // Multipliers from the linearized constraints at the step taken.
    if (split) {
      linearized_e_ += jnormal_e_;
      linearized_i_ += jnormal_i_;
    }
    linearized_e_ += alpha * jstep_e_;
    linearized_i_ += alpha * jstep_i_;
    lambda_e_ -= mu_ * linearized_e_;
    for (int i = 0; i < ev_.c_i().size(); ++i) {
      lambda_i_[i] = std::max(0.0, lambda_i_[i] - mu_ * linearized_i_[i]);
    }
    q = q_try_;
  }
  if (!st.converged && !st.budget_exhausted) {
    // Out of iterations: the last step's point has not been scored yet (ev_ is at q).
    ev_.ObjectiveGradient(q, q_prev_, M_, &grad_e_);
    st.max_violation = Violation();
    st.complementarity = Complementarity();
    KktResidual(&kkt_);
    st.kkt_residual = MaxAbs(kkt_);
  }
  if (!st.converged && best_score < std::numeric_limits<double>::infinity()) {
    const double score =
        std::max(st.max_violation / options_.constraint_tolerance, st.kkt_residual / kkt_tolerance);
    // (Also when the last iterate's residuals are NaN.)
    if (!(score <= best_score) || !Returnable(q)) {
      q = q_best_;
      lambda_e_ = lambda_e_best_;
      lambda_i_ = lambda_i_best_;
      // Its contacts from where they stood there: re-solved from a later iterate's, one may
      // land on another extremum of its pair (measured on the chain soak in line mode: an
      // iterate scored at a violation of 2e-16, evaluated again from a later one's contacts,
      // held its wires by sections on their far sides, 0.9 mm deep).
      // (One not yet anchored is the iterate the loop stopped at: q, its contacts as they are.)
      if (!best_pending) ev_.RewindStates(best_slot);
      ev_.Evaluate(q);
      st.max_violation = best_violation;
      st.kkt_residual = best_kkt;
      st.complementarity = Complementarity();
    }
  }
  // An unconverged solve (out of iterations or time, or stopped at the motion bound) may return
  // an iterate off its rows by more than their tolerance (measured on the chain soak: a line's
  // sections placed anew read a dip of 1.6e-8 m at the start, and every iterate that closed it
  // moved the clips beyond the motion bound, so the start was returned, tick after tick):
  // corrected onto them by the least motion, when that is a correction (within what the
  // finishing correction restores), not a solve.
  if (options_.restore_feasibility && !st.converged && q.allFinite() &&
      st.max_violation > options_.constraint_tolerance &&
      st.max_violation <= options_.finish_violation * options_.constraint_tolerance) {
    RestoreFeasibility(&q, &st);
  }
  if (!q.allFinite() || !lambda_e_.allFinite() || !lambda_i_.allFinite() ||
      !std::isfinite(st.max_violation)) {
    // Every iterate went wrong (no finite best one): undo the whole solve, so the next one
    // starts from where this one did (a NaN multiplier would otherwise persist and spoil every
    // later solve).
    SolveStats failed = InvalidInput(&q, st);
    failed.invalid_input = false;
    failed.iterations = st.iterations;
    return failed;
  }
  st.objective = ObjectiveAt(q);
  st.penalty = mu_;
  st.indefinite_steps = indefinite_steps_;
  if (options_.second_order_check) SecondOrderCheck(q, &st);
  return st;
}

}  // namespace tangent::optimizer
