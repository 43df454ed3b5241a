#pragma once

#include <Eigen/Core>

#include "optimizer/solver.h"

namespace tangent::optimizer {

/// The interaction modes of seed 000 §4.3 on top of Solver. A mode moves the goals through a
/// caller-supplied `set_goal(s)`, s ∈ [0, 1] from where the goals are now (s = 0) to where the
/// user wants them (s = 1), e.g. a position target interpolated between two points.
///   - Drag: the servo loop's mode: one warm Solver::Solve per new goal (no helper needed).
///   - Pull to goal: `steps` interpolated subgoals, one warm solve each (the mechanism is pulled
///     along the straight goal path).
///   - Solve for goal: one large move; whenever a solve fails to converge the remaining move is
///     halved (the configuration and multipliers restored first), down to 2^-max_depth of it.
struct ModeStats {
  int solves = 0;
  int subdivisions = 0;  ///< failed attempts that were split in half (solve for goal)
  bool reached = false;  ///< the last solve, at s = 1, converged
  double reached_fraction = 0.0;
  SolveStats last;
};

template <class SetGoal>
ModeStats PullToGoal(Solver* solver, Eigen::VectorXd* q, SetGoal&& set_goal, int steps) {
  ModeStats st;
  for (int k = 1; k <= steps; ++k) {
    const double s = static_cast<double>(k) / steps;
    set_goal(s);
    st.last = solver->Solve(q);
    ++st.solves;
    if (st.last.converged) st.reached_fraction = s;
  }
  st.reached = st.last.converged;
  return st;
}

template <class SetGoal>
ModeStats SolveForGoal(Solver* solver, Eigen::VectorXd* q, SetGoal&& set_goal, int max_depth = 12) {
  ModeStats st;
  double done = 0.0, next = 1.0;
  const double min_step = 1.0 / static_cast<double>(1 << max_depth);
  Eigen::VectorXd q_saved = *q;
  Eigen::VectorXd le = solver->equality_multipliers(), li = solver->inequality_multipliers();
  while (done < 1.0) {
    set_goal(next);
    st.last = solver->Solve(q);
    ++st.solves;
    if (st.last.converged) {
      done = next;
      st.reached_fraction = done;
      next = 1.0;
      q_saved = *q;
      le = solver->equality_multipliers();
      li = solver->inequality_multipliers();
      continue;
    }
    *q = q_saved;  // Back to the last converged configuration; try half the remaining move.
    solver->set_multipliers(le, li);
    if (next - done <= min_step) {
      set_goal(done);
      break;
    }
    next = 0.5 * (done + next);
    ++st.subdivisions;
  }
  st.reached = done == 1.0;
  return st;
}

}  // namespace tangent::optimizer
