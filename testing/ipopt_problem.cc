#include "testing/ipopt_problem.h"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>
#include <algorithm>

namespace tangent::optimizer::testing {

namespace {

class Nlp : public Ipopt::TNLP {
 public:
  explicit Nlp(const Problem& p) : p_(p), ev_(p) {
    n_ = p.mechanism().num_coordinates();
    me_ = p.num_equality_rows();
    mi_ = p.num_inequality_rows();
    H_.setZero(n_, n_);
  }
  void Reset(const Eigen::VectorXd& q0) {
    q0_ = q0;
    p_.mechanism().Metric(q0_, &M_);
    result_ = IpoptResult{};
  }
  IpoptResult& result() { return result_; }
  optimizer::ProblemData& data() { return ev_.data(); }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = n_;
    m = me_ + mi_;
    nnz_jac = n_ * (me_ + mi_);
    nnz_h = n_ * (n_ + 1) / 2;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index m,
                       Ipopt::Number* gl, Ipopt::Number* gu) override {
    std::fill(xl, xl + n, -2e19);
    std::fill(xu, xu + n, 2e19);
    std::fill(gl, gl + m, 0.0);
    std::fill(gu, gu + me_, 0.0);
    std::fill(gu + me_, gu + m, 2e19);
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    std::copy(q0_.data(), q0_.data() + n, x);
    return true;
  }
  bool eval_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    Load(n, x);
    f = ev_.Objective(q_, q0_, M_);
    return std::isfinite(f);
  }
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number* g) override {
    Load(n, x);
    Eigen::VectorXd grad(n_);
    ev_.ObjectiveGradient(q_, q0_, M_, &grad);
    std::copy(grad.data(), grad.data() + n, g);
    return grad.allFinite();
  }
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Index,
              Ipopt::Number* g) override {
    Load(n, x);
    std::copy(ev_.c_e().data(), ev_.c_e().data() + me_, g);
    std::copy(ev_.c_i().data(), ev_.c_i().data() + mi_, g + me_);
    return true;
  }
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Index m, Ipopt::Index,
                  Ipopt::Index* rows, Ipopt::Index* cols, Ipopt::Number* values) override {
    if (values == nullptr) {
      for (int i = 0, k = 0; i < m; ++i)
        for (int j = 0; j < n; ++j, ++k) rows[k] = i, cols[k] = j;
      return true;
    }
    Load(n, x);
    for (int i = 0, k = 0; i < m; ++i) {
      for (int j = 0; j < n; ++j, ++k)
        values[k] = i < me_ ? ev_.J_e()(i, j) : ev_.J_i()(i - me_, j);
    }
    return true;
  }
  bool eval_h(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number sigma, Ipopt::Index,
              const Ipopt::Number* lambda, bool, Ipopt::Index, Ipopt::Index* rows,
              Ipopt::Index* cols, Ipopt::Number* values) override {
    if (values == nullptr) {
      for (int i = 0, k = 0; i < n; ++i)
        for (int j = 0; j <= i; ++j, ++k) rows[k] = i, cols[k] = j;
      return true;
    }
    Load(n, x);
    // σ ∇²E + Σ λ_i ∇²g_i (IPOPT's Lagrangian is σ f + λᵀg).
    H_ = sigma * p_.least_astonishment() * M_;
    Eigen::VectorXd wo(p_.num_objective_rows());
    for (const Problem::Entry& o : p_.objectives()) {
      const auto J = ev_.J_o().middleRows(o.row, o.term->dim());
      H_.noalias() += sigma * o.weight * (J.transpose() * J);
      wo.segment(o.row, o.term->dim()) = sigma * o.weight * ev_.r_o().segment(o.row, o.term->dim());
    }
    ev_.AddCurvature(p_.objectives(), wo, &H_);
    ev_.AddCurvature(p_.equalities(), Eigen::Map<const Eigen::VectorXd>(lambda, me_), &H_);
    ev_.AddCurvature(p_.inequalities(), Eigen::Map<const Eigen::VectorXd>(lambda + me_, mi_), &H_);
    for (int i = 0, k = 0; i < n; ++i)
      for (int j = 0; j <= i; ++j, ++k) values[k] = H_(i, j);
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number* lambda, Ipopt::Number f,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    result_.q = Eigen::Map<const Eigen::VectorXd>(x, n);
    result_.objective = f;
    // IPOPT: ∇f + Σ λ ∇g = 0 (with bound multipliers); ours: ∇E = Jᵀλ.
    result_.lambda_e = -Eigen::Map<const Eigen::VectorXd>(lambda, me_);
    result_.lambda_i = -Eigen::Map<const Eigen::VectorXd>(lambda + me_, mi_);
  }

 private:
  void Load(int n, const Ipopt::Number* x) {
    q_ = Eigen::Map<const Eigen::VectorXd>(x, n);
    ev_.Evaluate(q_);
  }
  const Problem& p_;
  ProblemEvaluator ev_;
  int n_ = 0, me_ = 0, mi_ = 0;
  Eigen::VectorXd q0_, q_;
  Eigen::MatrixXd M_, H_;
  IpoptResult result_;
};

}  // namespace

struct IpoptSolver::Impl {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  Ipopt::SmartPtr<Nlp> nlp;
};

IpoptSolver::IpoptSolver(const Problem& problem, const IpoptOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->nlp = new Nlp(problem);
  Ipopt::OptionsList& o = *impl_->app->Options();
  o.SetIntegerValue("print_level", 0);
  o.SetStringValue("sb", "yes");
  o.SetNumericValue("tol", options.tolerance);
  o.SetNumericValue("constr_viol_tol", options.tolerance);
  o.SetIntegerValue("max_iter", options.max_iterations);
  o.SetStringValue("hessian_approximation",
                   problem.design_objectives().empty() ? "exact" : "limited-memory");
  impl_->app->Initialize();
}

IpoptSolver::~IpoptSolver() = default;

ProblemData& IpoptSolver::data() { return impl_->nlp->data(); }

IpoptResult IpoptSolver::Solve(const Eigen::VectorXd& q0) {
  impl_->nlp->Reset(q0);
  const Ipopt::ApplicationReturnStatus status = impl_->app->OptimizeTNLP(impl_->nlp);
  IpoptResult r = impl_->nlp->result();
  r.status = static_cast<int>(status);
  r.solved = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = impl_->app->Statistics();
  if (IsValid(stats)) r.iterations = stats->IterationCount();
  return r;
}

}  // namespace tangent::optimizer::testing
