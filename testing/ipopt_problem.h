#pragma once

// IPOPT on a tangent Problem, for cross-checks (tests) and peer timings (benchmarks): the same
// objective E (least astonishment about q_ref, weighted objective terms, design objectives),
// the same equalities (= 0) and inequalities (≥ 0), the same starting point. The Lagrangian
// Hessian is exact from the terms' curvature when the problem has no design objective;
// otherwise IPOPT's own limited-memory quasi-Newton model (the design objectives provide
// gradients only).

#include <memory>

#include <Eigen/Core>

#include "optimizer/evaluator.h"
#include "optimizer/problem.h"

namespace tangent::optimizer::testing {

struct IpoptResult {
  bool solved = false;  ///< IPOPT's Solve_Succeeded (or Solved_To_Acceptable_Level)
  int status = 0;       ///< Ipopt::ApplicationReturnStatus
  int iterations = 0;
  Eigen::VectorXd q;
  double objective = 0.0;
  /// Multipliers in tangent's sign convention (∇E = J_Eᵀλ_E + J_Iᵀλ_I, λ_I ≥ 0).
  Eigen::VectorXd lambda_e, lambda_i;
};

struct IpoptOptions {
  double tolerance = 1e-10;  ///< IPOPT's tol and constr_viol_tol
  int max_iterations = 3000;
};

class IpoptSolver {
 public:
  explicit IpoptSolver(const Problem& problem, const IpoptOptions& options = {});
  ~IpoptSolver();
  /// Solves from q0 (also least astonishment's q_ref).
  IpoptResult Solve(const Eigen::VectorXd& q0);
  /// The adapter's per-solve data (goal targets, tracked contacts).
  ProblemData& data();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tangent::optimizer::testing
