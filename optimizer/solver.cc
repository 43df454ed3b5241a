#include "optimizer/solver.h"

#include <chrono>

namespace tangent::optimizer {

Solver::Solver(const Problem& problem, const SolverOptions& options)
    : problem_(problem), options_(options), ev_(problem) {
  const Mechanism& m = problem.mechanism();
  n_ = m.num_coordinates();
  q_prev_.setZero(n_);
  g_.setZero(n_);
  step_.setZero(n_);
  q_try_.setZero(n_);
  shifted_.setZero(problem.num_inequality_rows());
  M_.setZero(n_, n_);
  H_.setZero(n_, n_);
  kkt_.setZero(n_);
  grad_e_.setZero(n_);
  linearized_e_.setZero(problem.num_equality_rows());
  linearized_i_.setZero(problem.num_inequality_rows());
  weights_.setZero(std::max({problem.num_equality_rows(), problem.num_inequality_rows(),
                             problem.num_objective_rows(), 1}));
  ldlt_ = Eigen::LDLT<Eigen::MatrixXd>(n_);
  Reset();
}

void Solver::Reset() {
  lambda_e_.setZero(problem_.num_equality_rows());
  lambda_i_.setZero(problem_.num_inequality_rows());
  mu_ = options_.penalty;
}

void Solver::AugmentedGradient() {
  // g = ∇L = ∇E − J_Eᵀ(λ_E − μ c_E) − J_Iᵀ max(0, λ_I − μ c_I), from ∇E in grad_e_.
  g_ = grad_e_;
  g_.noalias() -= ev_.J_e().transpose() * (lambda_e_ - mu_ * ev_.c_e());
  for (int i = 0; i < ev_.c_i().size(); ++i) {
    shifted_[i] = std::max(0.0, lambda_i_[i] - mu_ * ev_.c_i()[i]);
    if (shifted_[i] > 0.0) g_.noalias() -= shifted_[i] * ev_.J_i().row(i).transpose();
  }
}

double Solver::NewtonMatrix() {
  // H = w_la M + Σ w J_oᵀJ_o + μ J_EᵀJ_E + μ J_AᵀJ_A (A: rows with positive shifted multiplier,
  // as left by AugmentedGradient), plus the Lagrangian's curvature: objectives weighted by w r,
  // equalities by −λ_E, active inequalities by −λ_I.
  H_ = problem_.least_astonishment() * M_;
  for (const Problem::Entry& o : problem_.objectives()) {
    const auto J = ev_.J_o().middleRows(o.row, o.term->dim());
    H_.noalias() += o.weight * (J.transpose() * J);
  }
  // The objective's share of the matrix sets the damping's scale (1e-300: an empty objective).
  const double objective_scale = H_.diagonal().cwiseAbs().maxCoeff() + 1e-300;
  H_.noalias() += mu_ * (ev_.J_e().transpose() * ev_.J_e());
  for (int i = 0; i < ev_.c_i().size(); ++i) {
    if (shifted_[i] > 0.0) H_.noalias() += mu_ * (ev_.J_i().row(i).transpose() * ev_.J_i().row(i));
  }
  for (const Problem::Entry& o : problem_.objectives()) {
    weights_.segment(o.row, o.term->dim()) = o.weight * ev_.r_o().segment(o.row, o.term->dim());
  }
  ev_.AddCurvature(problem_.objectives(), weights_, &H_);
  weights_.head(ev_.c_e().size()) = -lambda_e_;
  ev_.AddCurvature(problem_.equalities(), weights_, &H_);
  for (int i = 0; i < ev_.c_i().size(); ++i) weights_[i] = shifted_[i] > 0.0 ? -lambda_i_[i] : 0.0;
  ev_.AddCurvature(problem_.inequalities(), weights_, &H_);
  return objective_scale;
}

void Solver::Normalize(Eigen::VectorXd* q) const {
  const Mechanism& m = problem_.mechanism();
  for (int b = 0; b < m.num_bodies(); ++b) {
    if (m.offset(b) >= 0) q->segment<4>(m.offset(b) + 3).normalize();
  }
}

double Solver::Violation() const {
  double v = ev_.c_e().size() ? ev_.c_e().cwiseAbs().maxCoeff() : 0.0;
  for (int i = 0; i < ev_.c_i().size(); ++i) v = std::max(v, -ev_.c_i()[i]);
  return v;
}

SolveStats Solver::Solve(Eigen::VectorXd* q_io) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Eigen::VectorXd& q = *q_io;
  q_prev_ = q;
  problem_.mechanism().Metric(q_prev_, &M_);
  SolveStats st;
  ev_.Evaluate(q);
  // Primal-dual augmented Lagrangian (stabilized SQP): Newton on
  //   ∇E − J_Eᵀλ_E − J_Iᵀλ_I = 0,   c_E + (λ_E − λ̄_E)/μ = 0   (and PHR-shifted inequalities)
  // with the proximal centre λ̄ the current multipliers. Eliminating Δλ leaves
  //   (∇²E − Σ λ_i ∇²c_i + μ JᵀJ) Δq = −(∇E − Jᵀ(λ − μc)),   λ ← λ − μ (c + J Δq),
  // i.e. the augmented-Lagrangian Newton step with the multipliers updated every iteration
  // from the linearized constraints. Near a warm start this is Newton on the KKT system
  // (quadratic convergence); the 1/μ block keeps redundant constraints regular.
  for (st.iterations = 0; st.iterations < options_.max_iterations; ++st.iterations) {
    // ∇E once per iteration: the KKT residual and the step's right-hand side both use it.
    ev_.ObjectiveGradient(q, q_prev_, M_, &grad_e_);
    st.max_violation = Violation();
    kkt_ = grad_e_;  // ∇E − J_Eᵀλ_E − J_Iᵀλ_I at the current multipliers.
    kkt_.noalias() -= ev_.J_e().transpose() * lambda_e_;
    kkt_.noalias() -= ev_.J_i().transpose() * lambda_i_;
    st.kkt_residual = kkt_.size() ? kkt_.cwiseAbs().maxCoeff() : 0.0;
    if (st.max_violation <= options_.constraint_tolerance &&
        st.kkt_residual <= options_.kkt_tolerance) {
      st.converged = true;
      break;
    }
    if (options_.time_budget_us > 0 &&
        std::chrono::duration<double, std::micro>(Clock::now() - start).count() >
            options_.time_budget_us) {
      st.budget_exhausted = true;
      break;
    }
    AugmentedGradient();
    const double objective_scale = NewtonMatrix();
    // Levenberg damping until positive definite (the Lagrangian's curvature may not be). Its
    // scale is the objective's part of the matrix, not μJᵀJ's: the curvature along a
    // mechanism's free motions is of the objective's size, and damping sized by μ|J|² (here
    // 1e6 larger) would shorten every Newton step (measured: half the step, 4.5 iterations
    // per warm solve instead of 3).
    double lm = options_.damping * objective_scale;
    H_.diagonal().array() += lm;
    for (int attempt = 0; attempt < 16; ++attempt) {
      ldlt_.compute(H_);
      if (ldlt_.info() == Eigen::Success && (ldlt_.vectorD().array() > 0.0).all()) break;
      const double more = std::max(1e-8 * objective_scale, 10 * lm);
      H_.diagonal().array() += more - lm;
      lm = more;
    }
    step_ = ldlt_.solve(-g_);
    // Safeguard for steps far from a solution (warm starts rarely need it): halve while the
    // violation would grow more than tenfold above the tolerance.
    double alpha = 1.0;
    for (int k = 0; k < 8; ++k) {
      q_try_ = q + alpha * step_;
      Normalize(&q_try_);
      linearized_e_.noalias() = ev_.c_e() + alpha * (ev_.J_e() * step_);
      linearized_i_.noalias() = ev_.c_i() + alpha * (ev_.J_i() * step_);
      ev_.Evaluate(q_try_);
      if (Violation() <= std::max(10.0 * st.max_violation, 1e3 * options_.constraint_tolerance))
        break;
      alpha *= 0.5;
    }
    // Multipliers from the linearized constraints at the step taken.
    lambda_e_ -= mu_ * linearized_e_;
    for (int i = 0; i < ev_.c_i().size(); ++i) {
      lambda_i_[i] = std::max(0.0, lambda_i_[i] - mu_ * linearized_i_[i]);
    }
    q = q_try_;
  }
  st.objective = ev_.Objective(q, q_prev_, M_);
  st.penalty = mu_;
  return st;
}

}  // namespace tangent::optimizer
