#include "optimizer/evaluator.h"

namespace tangent::optimizer {

ProblemEvaluator::ProblemEvaluator(const Problem& problem) : problem_(problem) {
  const Mechanism& m = problem.mechanism();
  const int n = m.num_coordinates();
  m.Poses(m.InitialCoordinates(), &poses_);
  c_e_.setZero(problem.num_equality_rows());
  c_i_.setZero(problem.num_inequality_rows());
  r_o_.setZero(problem.num_objective_rows());
  J_e_.setZero(problem.num_equality_rows(), n);
  J_i_.setZero(problem.num_inequality_rows(), n);
  J_o_.setZero(problem.num_objective_rows(), n);
  int max_dim = 1;
  for (const auto* list : {&problem.equalities(), &problem.inequalities(), &problem.objectives()}) {
    for (const auto& e : *list) max_dim = std::max(max_dim, e.term->dim());
  }
  scratch_a_.setZero(max_dim, 7);
  scratch_b_.setZero(max_dim, 7);
}

void ProblemEvaluator::Evaluate(const Eigen::VectorXd& q) {
  const Mechanism& m = problem_.mechanism();
  for (int i = 0; i < m.num_bodies(); ++i) {
    if (m.offset(i) >= 0) {
      poses_[static_cast<size_t>(i)] = BodyPose::FromCoordinates(q.segment<7>(m.offset(i)));
    }
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

double ProblemEvaluator::Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                   const Eigen::MatrixXd& M) const {
  double e = 0.5 * problem_.least_astonishment() * (q - q_ref).dot(M * (q - q_ref));
  for (const Problem::Entry& o : problem_.objectives()) {
    e += 0.5 * o.weight * r_o_.segment(o.row, o.term->dim()).squaredNorm();
  }
  return e;
}

void ProblemEvaluator::ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                         const Eigen::MatrixXd& M, Eigen::VectorXd* g) const {
  g->noalias() = problem_.least_astonishment() * (M * (q - q_ref));
  for (const Problem::Entry& o : problem_.objectives()) {
    g->noalias() += o.weight * (J_o_.middleRows(o.row, o.term->dim()).transpose() *
                                r_o_.segment(o.row, o.term->dim()));
  }
}

void ProblemEvaluator::AddCurvature(const std::vector<Problem::Entry>& list,
                                    const Eigen::VectorXd& weights, Eigen::MatrixXd* H) const {
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
    if (oa >= 0) H->block<7, 7>(oa, oa) += haa;
    if (ob >= 0) H->block<7, 7>(ob, ob) += hbb;
    if (oa >= 0 && ob >= 0) {
      H->block<7, 7>(oa, ob) += hab;
      H->block<7, 7>(ob, oa) += hab.transpose();
    }
  }
}

}  // namespace tangent::optimizer
