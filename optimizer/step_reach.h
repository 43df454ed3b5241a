#pragma once

// The step reach (SolverOptions::step_reach, docs/stability.md "Step reach"): how much of a
// Newton step keeps every contact row's two copies of its contact point within the row's reach
// (Term::Reach) of each other. Split from solver.cc by concept.

#include <Eigen/Core>

#include "optimizer/problem.h"

namespace tangent::optimizer {

/// The largest fraction (≤ 1) of `step` from q within every inequality row's reach, from the
/// poses before and after the full step (exact rigid displacements of the contact points).
/// Allocation free.
double ReachFraction(const Problem& problem, const ProblemData& data, const Eigen::VectorXd& q,
                     const Eigen::VectorXd& step);

}  // namespace tangent::optimizer
