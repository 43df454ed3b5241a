// The clearance guard (optimizer/clearance_guard.h): its motion bound holds every point of a
// body within reach along a step's whole segment, is exact for a pure translation, and the
// fraction it admits is the largest that keeps each certified pair within its share.

#include "optimizer/clearance_guard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>

#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "optimizer/goals.h"
#include "optimizer/solver.h"
#include "testing/alloc_counter.h"

namespace tangent::optimizer {
namespace {

// A fixed body and two moving ones.
Mechanism Bodies() {
  Mechanism m;
  Body ground;
  ground.fixed = true;
  m.AddBody(ground);
  m.AddBody(Body{});
  m.AddBody(Body{});
  return m;
}

Eigen::Vector4d RandomQuaternion(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Vector4d(n(rng), n(rng), n(rng), n(rng)).normalized();
}

// World position of body-frame point x at coordinates q (moving body at offset o).
Eigen::Vector3d Place(const Eigen::VectorXd& q, int o, const Eigen::Vector3d& x) {
  const Eigen::Vector4d Q = q.segment<4>(o + 3).normalized();
  return q.segment<3>(o) + Eigen::Quaterniond(Q[0], Q[1], Q[2], Q[3]) * x;
}

TEST(ClearanceGuardTest, TheMotionBoundHoldsEveryPointAlongTheSegment) {
  const Mechanism m = Bodies();
  ClearanceGuard guard;
  const double reach = 0.03;
  guard.Configure(m, {{0, 1}}, {0.0, reach, reach});
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double worst_ratio = 0.0;
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::VectorXd q_ref(14), q(14), step(14);
    for (int b = 0; b < 2; ++b) {
      const int o = 7 * b;
      q_ref.segment<3>(o) = 0.01 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
      q_ref.segment<4>(o + 3) = RandomQuaternion(rng);
      // Near the reference (servo steps) or anywhere (the bound must hold regardless).
      const double s = trial % 3 == 0 ? 1.0 : 0.05;
      q.segment<3>(o) =
          q_ref.segment<3>(o) + 0.01 * s * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
      q.segment<4>(o + 3) = (q_ref.segment<4>(o + 3) + s * RandomQuaternion(rng)).normalized() *
                            (1.0 + 0.1 * unit(rng));
      step.segment<3>(o) = 0.01 * s * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
      step.segment<4>(o + 3) = s * RandomQuaternion(rng);
    }
    const double alpha = 0.5 * (1.0 + unit(rng));
    const double bound = guard.Motion(1, q_ref, q, step, alpha);
    // Points of the body within reach, at 60 places along the segment.
    double largest = 0.0;
    for (int p = 0; p < 20; ++p) {
      Eigen::Vector3d x(unit(rng), unit(rng), unit(rng));
      x *= reach * std::cbrt(0.5 * (1.0 + unit(rng))) / x.norm();
      if (p == 0) x = reach * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
      for (int i = 0; i <= 60; ++i) {
        const Eigen::VectorXd qs = q + (alpha * i / 60.0) * step;
        largest = std::max(largest, (Place(qs, 0, x) - Place(q_ref, 0, x)).norm());
      }
    }
    EXPECT_LE(largest, bound * (1.0 + 1e-12)) << "trial " << trial;
    worst_ratio = std::max(worst_ratio, largest / bound);
  }
  std::printf("largest sampled displacement / bound: %.3f\n", worst_ratio);
  EXPECT_GT(worst_ratio, 0.5);  // not a bound so loose that it says nothing
  // A pure translation: the bound is the displacement itself.
  Eigen::VectorXd q_ref(14), step = Eigen::VectorXd::Zero(14);
  q_ref << 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0;
  step.head<3>() = Eigen::Vector3d(3e-3, -4e-3, 0);
  EXPECT_NEAR(guard.Motion(1, q_ref, q_ref, step, 1.0), 5e-3, 1e-15);
  EXPECT_EQ(guard.Motion(0, q_ref, q_ref, step, 1.0), 0.0);  // the fixed body
}

TEST(ClearanceGuardTest, TheFractionIsTheLargestWithinEachPairsShare) {
  const Mechanism m = Bodies();
  ClearanceGuard guard;
  guard.Configure(m, {{0, 1}, {1, 2}, {0, 2}}, {0.0, 0.02, 0.01});
  Eigen::VectorXd q = m.InitialCoordinates();
  EXPECT_FALSE(guard.armed());
  const double inf = std::numeric_limits<double>::infinity();
  const double clearance[3] = {2e-3, inf, 5e-3};
  auto at = [&](int b) { return Eigen::Matrix<double, 7, 1>(q.segment<7>(m.offset(b))); };
  // (The guard asks only for the moving bodies' poses.)
  ASSERT_TRUE(guard.Adopt(q, at, clearance));
  EXPECT_TRUE(guard.armed());
  // Body 1 moves 10 mm toward the ground: its pair (0, 1) admits 0.9 x 2 mm, a fifth of it.
  Eigen::VectorXd step = Eigen::VectorXd::Zero(q.size());
  step[2] = -10e-3;
  const long before = testing::AllocationCount();
  const double alpha = guard.Fraction(q, step);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_NEAR(alpha, 0.18, 1e-6);
  EXPECT_LE(guard.Motion(1, q, q, step, alpha), ClearanceGuard::kShare * 2e-3);
  EXPECT_GT(guard.Motion(1, q, q, step, alpha + 1e-5), ClearanceGuard::kShare * 2e-3);
  // Body 2 turns: its pair (0, 2) bounds it by its reach's chord; (1, 2) is not certified.
  step.setZero();
  step.segment<4>(m.offset(2) + 3) = Eigen::Vector4d(0, 0, 0, 1);  // towards a half turn
  const double beta = guard.Fraction(q, step);
  EXPECT_GT(beta, 0.0);
  EXPECT_LT(beta, 1.0);
  EXPECT_LE(guard.Motion(2, q, q, step, beta), ClearanceGuard::kShare * 5e-3 * (1 + 1e-9));
  // A small step within every share is taken whole.
  step.setZero();
  step[m.offset(1)] = 1e-4;
  EXPECT_EQ(guard.Fraction(q, step), 1.0);
  // A certificate the configuration has already moved beyond is refused (the guard keeps its
  // own), one that holds it is taken.
  Eigen::VectorXd moved = q;
  moved[m.offset(1) + 2] -= 1.9e-3;
  const double tight[3] = {1e-3, inf, inf};
  EXPECT_FALSE(guard.Adopt(
      moved, [&](int b) { return at(b); }, tight));
  EXPECT_EQ(guard.clearance()[0], 2e-3);
  const double wide[3] = {3e-3, inf, inf};
  EXPECT_TRUE(guard.Adopt(
      moved, [&](int b) { return at(b); }, wide));
  // Nothing certified: disarmed, every step whole.
  const double none[3] = {inf, inf, inf};
  EXPECT_TRUE(guard.Adopt(
      q, [&](int b) { return at(b); }, none));
  EXPECT_FALSE(guard.armed());
}

TEST(ClearanceGuardTest, TheMotionBoundHoldsMarkedBodiesOnlyAndIsTight) {
  // The tick motion bound (SolverOptions::max_solve_motion): a marked body's points stay
  // within the bound of where they were at q_ref along the whole step, the fraction is the
  // largest that does, and unmarked bodies, armed or not, are left alone.
  const Mechanism m = Bodies();
  ClearanceGuard guard;
  guard.Configure(m, {}, {0.0, 0.02, 0.01});
  EXPECT_FALSE(guard.armed());
  std::mt19937_64 rng(33);
  std::normal_distribution<double> n(0.0, 1.0);
  const double bound = 5e-5;
  int bounded = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd q = m.InitialCoordinates();
    for (int b = 1; b <= 2; ++b) {
      const int o = m.offset(b);
      q.segment<3>(o) = 1e-3 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      q.segment<4>(o + 3) = RandomQuaternion(rng);
    }
    Eigen::VectorXd q_ref = q, step = Eigen::VectorXd::Zero(q.size());
    for (int b = 1; b <= 2; ++b) {  // a start already partway out, a step of up to ~0.4 mm
      const int o = m.offset(b);
      q.segment<3>(o) += 1e-5 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      step.segment<3>(o) = 1e-4 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      step.segment<4>(o + 3) = 1e-2 * Eigen::Vector4d(n(rng), n(rng), n(rng), n(rng));
    }
    guard.ClearBounds();
    EXPECT_EQ(guard.MotionFraction(q_ref, q, step, 1.0, bound), 1.0);  // nothing marked
    guard.Bound(1, true);
    const long before = testing::AllocationCount();
    const double alpha = guard.MotionFraction(q_ref, q, step, 1.0, bound);
    EXPECT_EQ(testing::AllocationCount() - before, 0);
    if (guard.Motion(1, q_ref, q, step, 0.0) > bound) {
      EXPECT_EQ(alpha, 0.0);  // already beyond: no step away from q_ref (μ only grows)
      continue;
    }
    EXPECT_LE(guard.Motion(1, q_ref, q, step, alpha), bound);
    if (alpha < 1.0) {
      ++bounded;
      EXPECT_GT(guard.Motion(1, q_ref, q, step, alpha + 1e-5), bound);
    }
    // Body 2 is not marked: however far it goes, it does not shorten the step.
    Eigen::VectorXd far = step;
    far.segment<3>(m.offset(2)) *= 100.0;
    EXPECT_EQ(guard.MotionFraction(q_ref, q, far, 1.0, bound), alpha);
    // Every point within the reach stays within the bound at the fraction's end.
    const Eigen::VectorXd end = q + alpha * step;
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d x =
          0.02 * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * std::abs(n(rng)) / 3.0;
      if (x.norm() > 0.02) continue;
      EXPECT_LE((Place(end, m.offset(1), x) - Place(q_ref, m.offset(1), x)).norm(),
                bound * (1 + 1e-9));
    }
  }
  EXPECT_GT(bounded, 50);  // the bound acted on a good share of the steps
}

TEST(ClearanceGuardTest, TheSolverAsksForItsMarksOnceWhenItStepsAndKeepsToTheBound) {
  // A free body pulled 10 mm by a goal, the solve motion bound 1 mm: the marker is asked once,
  // at the first step; the body ends within the bound of where it started. A solve that takes
  // no step never asks; a marker that marks nothing leaves the solve unbounded.
  const Mechanism m = Bodies();
  ClearanceGuard guard;
  guard.Configure(m, {}, {0.0, 0.02, 0.02});
  Problem p(m);
  p.AddObjective(PositionGoal({1, {0, 0, 0}}, {0.01, 0, 0}), 1.0);
  SolverOptions options;
  options.max_solve_motion = 1e-3;
  Solver solver(p, options);
  solver.set_clearance_guard(&guard);
  struct Marker {
    ClearanceGuard* guard;
    bool mark;
    int calls = 0;
  } marker{&guard, true};
  solver.set_motion_marker(
      [](void* c) {
        auto* k = static_cast<Marker*>(c);
        ++k->calls;
        k->guard->ClearBounds();
        k->guard->Bound(1, k->mark);
        return k->mark;
      },
      &marker);
  const Eigen::VectorXd start = m.InitialCoordinates();
  Eigen::VectorXd q = start;
  const long before = testing::AllocationCount();
  SolveStats st = solver.Solve(&q);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_EQ(marker.calls, 1);
  EXPECT_TRUE(st.motion_marked);
  EXPECT_GT(st.motion_bounded_steps, 0);
  EXPECT_LE(guard.Motion(1, start, q, q, 0.0), 1e-3 * (1 + 1e-9));
  EXPECT_GT(guard.Motion(1, start, q, q, 0.0), 0.99e-3);  // as far as the bound lets it
  // At the goal: no step, no question.
  Eigen::VectorXd at_goal = start;
  at_goal[m.offset(1)] = 0.01;
  marker.calls = 0;
  st = solver.Solve(&at_goal);
  EXPECT_EQ(marker.calls, 0);
  EXPECT_FALSE(st.motion_marked);
  // Nothing marked: the whole way (less the step penalty's 0.1 %: least astonishment 1e-3).
  marker.mark = false;
  q = start;
  st = solver.Solve(&q);
  EXPECT_EQ(marker.calls, 1);
  EXPECT_FALSE(st.motion_marked);
  EXPECT_EQ(st.motion_bounded_steps, 0);
  EXPECT_NEAR(q[m.offset(1)], 0.01 / (1 + 1e-3), 1e-9);
}

TEST(ClearanceGuardTest, AnUnconvergedSolveReturnsNoIterateBeyondTheBoundOfAReturnMarkedBody) {
  // Bodies 1 and 2 pulled by goals, body 1 marked for the return bound (ClearanceGuard::
  // BoundReturn, 1 mm): its steps are free, and a solve that converges keeps its solution
  // however far it went; one cut short by its iteration budget returns the best iterate within
  // the bound of the start (here the start itself), and one whose last iterate lies within the
  // bound returns that. Unmarked, the cut-short solve returns its last iterate.
  const Mechanism m = Bodies();
  ClearanceGuard guard;
  guard.Configure(m, {}, {0.0, 0.02, 0.02});
  const double bound = 1e-3;
  struct Marker {
    ClearanceGuard* guard;
    bool mark;
  } marker{&guard, true};
  auto solve = [&](double pull, int iterations, Eigen::VectorXd* q) {
    Problem p(m);
    p.AddObjective(PositionGoal({1, {0, 0, 0}}, {pull, 0, 0}), 1.0);
    p.AddObjective(PositionGoal({2, {0, 0, 0}}, {0, pull, 0}), 1.0);
    SolverOptions options;
    options.max_solve_motion = bound;
    options.max_iterations = iterations;
    Solver solver(p, options);
    solver.set_clearance_guard(&guard);
    solver.set_motion_marker(
        [](void* c) {
          auto* k = static_cast<Marker*>(c);
          k->guard->ClearBounds();
          k->guard->ClearReturnBounds();
          k->guard->BoundReturn(1, k->mark);
          return false;  // no body marked for the steps
        },
        &marker);
    *q = m.InitialCoordinates();
    const long before = testing::AllocationCount();
    const SolveStats st = solver.Solve(q);
    EXPECT_EQ(testing::AllocationCount() - before, 0);
    EXPECT_EQ(st.motion_bounded_steps, 0);
    return st;
  };
  const Eigen::VectorXd start = m.InitialCoordinates();
  Eigen::VectorXd q;
  // Converged 10 mm away: kept.
  SolveStats st = solve(0.01, 10, &q);
  EXPECT_TRUE(st.converged);
  EXPECT_NEAR(q[m.offset(1)], 0.01 / (1 + 1e-3), 1e-9);
  // One iteration (Newton's step to the goal, not yet known converged): the start, both bodies.
  st = solve(0.01, 1, &q);
  EXPECT_FALSE(st.converged);
  EXPECT_EQ(guard.Motion(1, start, q, q, 0.0), 0.0);
  EXPECT_EQ(guard.Motion(2, start, q, q, 0.0), 0.0);
  // A pull of half the bound: the last iterate, within it.
  st = solve(0.5 * bound, 1, &q);
  EXPECT_FALSE(st.converged);
  EXPECT_NEAR(q[m.offset(1)], 0.5 * bound / (1 + 1e-3), 1e-9);
  // Unmarked: the last iterate, 10 mm away.
  marker.mark = false;
  st = solve(0.01, 1, &q);
  EXPECT_FALSE(st.converged);
  EXPECT_NEAR(q[m.offset(1)], 0.01 / (1 + 1e-3), 1e-9);
}

TEST(ClearanceGuardTest, ASolveAtItsMotionBoundStillRestoresItsContact) {
  // A probe 1e-7 m into a floor, pulled along it (and onto it) by a goal 10 mm away, its solve
  // motion bound 0.1 mm: the first Newton step leaves the bound most of the way. With
  // SolverOptions::bounded_normal_step the step's normal part, which cancels the floor's
  // linearized row, is taken whole and only the rest is shortened (Solver::SplitBoundedStep),
  // so the solve ends on the floor at the bound. A shortened whole step takes 1 % of the
  // correction and then stands at the bound, every later step cut to nothing: the paperclip
  // soak's freeze (docs/reliability.md).
  const nurbs::NurbsSurface floor = nurbs::MakePlanePatch(
      Eigen::Vector3d(-0.05, -0.05, 0.0), Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0, 0.1, 0));
  Mechanism m;
  const int fixed = m.AddBody(Body{"floor", true});
  Body probe_body{"probe"};
  probe_body.pose << 0, 0, -1e-7, 1, 0, 0, 0;
  const int probe = m.AddBody(probe_body);
  ClearanceGuard guard;
  guard.Configure(m, {}, {0.0, 0.0});
  Problem p(m);
  const Attachment tip{probe, {0, 0, 0}};
  p.AddObjective(MakePositionGoal(tip, {0.01, 0, -0.001}), 1.0);
  p.AddInequality(MakePointOnSurface(tip, fixed, &floor, {0.5, 0.5}));
  SolverOptions options;
  options.max_solve_motion = 1e-4;
  options.bounded_normal_step = true;
  auto guarded = [&](Solver* s) {  // the probe marked for the bound at each solve's first step
    s->set_clearance_guard(&guard);
    s->set_motion_marker(
        [](void* g) {
          static_cast<ClearanceGuard*>(g)->Bound(1, true);
          return true;
        },
        &guard);
  };
  Solver solver(p, options);
  guarded(&solver);
  const Eigen::VectorXd start = m.InitialCoordinates();
  Eigen::VectorXd q = start;
  const long before = testing::AllocationCount();
  const SolveStats st = solver.Solve(&q);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_GT(st.motion_bounded_steps, 0);
  EXPECT_FALSE(st.stopped_at_bound);
  EXPECT_LE(guard.Motion(1, start, q, q, 0.0), 1e-4 * (1 + 1e-9));
  EXPECT_GT(q[m.offset(1)], 0.9e-4);  // along the floor, as far as the bound lets it
  EXPECT_LE(st.max_violation, options.constraint_tolerance);
  EXPECT_NEAR(q[m.offset(1) + 2], 0.0, options.constraint_tolerance);
  // The floor carries the goal's pull onto it (1 mm of the goal's unit weight), not more.
  EXPECT_NEAR(solver.inequality_multipliers()[0], 1e-3, 1e-5);

  // Without the split (the default) the solve stops at the bound, and says so; its multiplier
  // is what the first step left, not μ c more for every iteration after it (μ c = 0.1 an
  // iteration here). The iterate it stops at stands through the floor (5e-8 m or more: 1 % of
  // the correction taken), and is returned moved onto it by the least motion
  // (Solver::RestoreFeasibility), within the bound, allocating nothing.
  options.bounded_normal_step = false;
  Solver plain(p, options);
  guarded(&plain);
  q = start;
  const long before_plain = testing::AllocationCount();
  const SolveStats stopped = plain.Solve(&q);
  EXPECT_EQ(testing::AllocationCount() - before_plain, 0);
  EXPECT_TRUE(stopped.stopped_at_bound);
  EXPECT_FALSE(stopped.converged);
  EXPECT_LT(stopped.iterations, 5);
  EXPECT_LT(plain.inequality_multipliers()[0], 1e-2);
  EXPECT_GE(stopped.corrections, 1);
  EXPECT_LE(stopped.max_violation, options.constraint_tolerance);
  EXPECT_GE(q[m.offset(1) + 2], -options.constraint_tolerance);
  EXPECT_LE(guard.Motion(1, start, q, q, 0.0), 1e-4 * (1 + 1e-9));

  // The correction off: the iterate the solve stopped at, through the floor.
  options.restore_feasibility = false;
  Solver unrestored(p, options);
  guarded(&unrestored);
  q = start;
  const SolveStats through = unrestored.Solve(&q);
  EXPECT_TRUE(through.stopped_at_bound);
  EXPECT_EQ(through.corrections, 0);
  EXPECT_GT(through.max_violation, 5e-8);
  EXPECT_LT(q[m.offset(1) + 2], -5e-8);
}

}  // namespace
}  // namespace tangent::optimizer
