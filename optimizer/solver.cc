#include "optimizer/solver.h"

#include <chrono>

namespace tangent::optimizer {

Solver::Solver(const Problem& problem, const SolverOptions& options)
    : problem_(problem), options_(options) {
  const Mechanism& m = problem.mechanism();
  n_ = m.num_coordinates();
  m.Poses(m.InitialCoordinates(), &poses_);
  q_prev_.setZero(n_);
  g_.setZero(n_);
  step_.setZero(n_);
  q_try_.setZero(n_);
  c_e_.setZero(problem.num_equality_rows());
  c_i_.setZero(problem.num_inequality_rows());
  r_o_.setZero(problem.num_objective_rows());
  shifted_.setZero(problem.num_inequality_rows());
  J_e_.setZero(problem.num_equality_rows(), n_);
  J_i_.setZero(problem.num_inequality_rows(), n_);
  J_o_.setZero(problem.num_objective_rows(), n_);
  M_.setZero(n_, n_);
  H_.setZero(n_, n_);
  kkt_.setZero(n_);
  linearized_e_.setZero(problem.num_equality_rows());
  linearized_i_.setZero(problem.num_inequality_rows());
  weights_.setZero(std::max({problem.num_equality_rows(), problem.num_inequality_rows(),
                             problem.num_objective_rows(), 1}));
  int max_dim = 1;
  for (const auto* list : {&problem.equalities(), &problem.inequalities(), &problem.objectives()}) {
    for (const auto& e : *list) max_dim = std::max(max_dim, e.term->dim());
  }
  scratch_a_.setZero(max_dim, 7);
  scratch_b_.setZero(max_dim, 7);
  ldlt_ = Eigen::LDLT<Eigen::MatrixXd>(n_);
  Reset();
}

void Solver::Reset() {
  lambda_e_.setZero(problem_.num_equality_rows());
  lambda_i_.setZero(problem_.num_inequality_rows());
  mu_ = options_.penalty;
}

void Solver::Evaluate(const Eigen::VectorXd& q) {
  const Mechanism& m = problem_.mechanism();
  for (int i = 0; i < m.num_bodies(); ++i) {
    if (m.offset(i) >= 0)
      poses_[static_cast<size_t>(i)] = BodyPose::FromCoordinates(q.segment<7>(m.offset(i)));
  }
  auto fill = [&](const std::vector<Problem::Entry>& list, Eigen::VectorXd* c, Eigen::MatrixXd* J) {
    for (const Problem::Entry& e : list) {
      const int d = e.term->dim();
      auto ja = scratch_a_.topRows(d);
      auto jb = scratch_b_.topRows(d);
      e.term->Evaluate(poses_, c->segment(e.row, d), ja, jb);
      J->middleRows(e.row, d).setZero();
      const int oa = m.offset(e.term->body_a());
      const int ob = e.term->body_b() >= 0 ? m.offset(e.term->body_b()) : -1;
      if (oa >= 0) J->block(e.row, oa, d, 7) = ja;
      if (ob >= 0) J->block(e.row, ob, d, 7) += jb;  // += : a term may name one body twice.
    }
  };
  fill(problem_.equalities(), &c_e_, &J_e_);
  fill(problem_.inequalities(), &c_i_, &J_i_);
  fill(problem_.objectives(), &r_o_, &J_o_);
}

void Solver::Gradient(const Eigen::VectorXd& q, bool with_matrix) {
  // g = ∇L = w_la M (q − q_prev) + Σ w J_oᵀ r_o − J_Eᵀ(λ_E − μ c_E) − J_Iᵀ max(0, λ_I − μ c_I)
  // and, when asked, its Gauss–Newton matrix.
  const double w_la = problem_.least_astonishment();
  g_.noalias() = w_la * (M_ * (q - q_prev_));
  if (with_matrix) H_ = w_la * M_;
  for (const Problem::Entry& o : problem_.objectives()) {
    const auto J = J_o_.middleRows(o.row, o.term->dim());
    g_.noalias() += o.weight * (J.transpose() * r_o_.segment(o.row, o.term->dim()));
    if (with_matrix) H_.noalias() += o.weight * (J.transpose() * J);
  }
  g_.noalias() -= J_e_.transpose() * (lambda_e_ - mu_ * c_e_);
  if (with_matrix) H_.noalias() += mu_ * (J_e_.transpose() * J_e_);
  for (int i = 0; i < c_i_.size(); ++i) {
    shifted_[i] = std::max(0.0, lambda_i_[i] - mu_ * c_i_[i]);
    if (shifted_[i] > 0.0) {
      g_.noalias() -= shifted_[i] * J_i_.row(i).transpose();
      if (with_matrix) H_.noalias() += mu_ * (J_i_.row(i).transpose() * J_i_.row(i));
    }
  }
}

void Solver::AddCurvature(const std::vector<Problem::Entry>& list, const Eigen::VectorXd& weights) {
  const Mechanism& m = problem_.mechanism();
  Term::Matrix7d haa, hab, hbb;
  for (const Problem::Entry& e : list) {
    if (!e.term->has_hessian()) continue;
    const int d = e.term->dim();
    haa.setZero();
    hab.setZero();
    hbb.setZero();
    e.term->AddWeightedHessian(poses_, weights.segment(e.row, d), &haa, &hab, &hbb);
    const int oa = m.offset(e.term->body_a());
    const int ob = e.term->body_b() >= 0 ? m.offset(e.term->body_b()) : -1;
    if (oa >= 0) H_.block<7, 7>(oa, oa) += haa;
    if (ob >= 0) H_.block<7, 7>(ob, ob) += hbb;
    if (oa >= 0 && ob >= 0) {
      H_.block<7, 7>(oa, ob) += hab;
      H_.block<7, 7>(ob, oa) += hab.transpose();
    }
  }
}

void Solver::Normalize(Eigen::VectorXd* q) const {
  const Mechanism& m = problem_.mechanism();
  for (int b = 0; b < m.num_bodies(); ++b) {
    if (m.offset(b) >= 0) q->segment<4>(m.offset(b) + 3).normalize();
  }
}

double Solver::Violation() const {
  double v = c_e_.size() ? c_e_.cwiseAbs().maxCoeff() : 0.0;
  for (int i = 0; i < c_i_.size(); ++i) v = std::max(v, -c_i_[i]);
  return v;
}

SolveStats Solver::Solve(Eigen::VectorXd* q_io) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Eigen::VectorXd& q = *q_io;
  q_prev_ = q;
  problem_.mechanism().Metric(q_prev_, &M_);
  const double w_la = problem_.least_astonishment();
  SolveStats st;
  Evaluate(q);
  // Primal-dual augmented Lagrangian (stabilized SQP): Newton on
  //   ∇E − J_Eᵀλ_E − J_Iᵀλ_I = 0,   c_E + (λ_E − λ̄_E)/μ = 0   (and PHR-shifted inequalities)
  // with the proximal centre λ̄ the current multipliers. Eliminating Δλ leaves
  //   (∇²E − Σ λ_i ∇²c_i + μ JᵀJ) Δq = −(∇E − Jᵀ(λ − μc)),   λ ← λ − μ (c + J Δq),
  // i.e. the augmented-Lagrangian Newton step with the multipliers updated every iteration
  // from the linearized constraints. Near a warm start this is Newton on the KKT system
  // (quadratic convergence); the 1/μ block keeps redundant constraints regular.
  for (st.iterations = 0; st.iterations < options_.max_iterations; ++st.iterations) {
    Gradient(q, /*with_matrix=*/false);  // Also fills shifted_ = max(0, λ_I − μ c_I).
    // KKT residual of the current iterate with the multipliers it would update to at Δq = 0.
    st.max_violation = Violation();
    {
      // ∇E − J_Eᵀλ_E − J_Iᵀλ_I at the current multipliers.
      kkt_.noalias() = w_la * (M_ * (q - q_prev_));
      for (const Problem::Entry& o : problem_.objectives()) {
        kkt_.noalias() += o.weight * (J_o_.middleRows(o.row, o.term->dim()).transpose() *
                                      r_o_.segment(o.row, o.term->dim()));
      }
      kkt_.noalias() -= J_e_.transpose() * lambda_e_;
      kkt_.noalias() -= J_i_.transpose() * lambda_i_;
      st.kkt_residual = kkt_.size() ? kkt_.cwiseAbs().maxCoeff() : 0.0;
    }
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
    Gradient(q, /*with_matrix=*/true);
    // Curvature of the Lagrangian: objectives weighted by w r, equalities by −λ_E, active
    // inequalities by −λ_I (rows with a positive shifted multiplier).
    for (const Problem::Entry& o : problem_.objectives()) {
      weights_.segment(o.row, o.term->dim()) = o.weight * r_o_.segment(o.row, o.term->dim());
    }
    AddCurvature(problem_.objectives(), weights_);
    weights_.head(c_e_.size()) = -lambda_e_;
    AddCurvature(problem_.equalities(), weights_);
    for (int i = 0; i < c_i_.size(); ++i) weights_[i] = shifted_[i] > 0.0 ? -lambda_i_[i] : 0.0;
    AddCurvature(problem_.inequalities(), weights_);
    // Levenberg damping until positive definite (the Lagrangian's curvature may not be).
    const double diag = H_.diagonal().cwiseAbs().maxCoeff() + 1e-300;
    double lm = options_.damping * diag;
    H_.diagonal().array() += lm;
    for (int attempt = 0; attempt < 12; ++attempt) {
      ldlt_.compute(H_);
      if (ldlt_.info() == Eigen::Success && (ldlt_.vectorD().array() > 0.0).all()) break;
      const double more = std::max(1e-8 * diag, 10 * lm);
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
      linearized_e_.noalias() = c_e_ + alpha * (J_e_ * step_);
      linearized_i_.noalias() = c_i_ + alpha * (J_i_ * step_);
      Evaluate(q_try_);
      if (Violation() <= std::max(10.0 * st.max_violation, 1e3 * options_.constraint_tolerance))
        break;
      alpha *= 0.5;
    }
    // Multipliers from the linearized constraints at the step taken.
    lambda_e_ -= mu_ * linearized_e_;
    for (int i = 0; i < c_i_.size(); ++i)
      lambda_i_[i] = std::max(0.0, lambda_i_[i] - mu_ * linearized_i_[i]);
    q = q_try_;
  }
  st.objective = 0.5 * w_la * (q - q_prev_).dot(M_ * (q - q_prev_));
  for (const Problem::Entry& o : problem_.objectives()) {
    st.objective += 0.5 * o.weight * r_o_.segment(o.row, o.term->dim()).squaredNorm();
  }
  st.penalty = mu_;
  return st;
}

}  // namespace tangent::optimizer
