// The augmented-Lagrangian solver on the spatial four-bar of seed 001 Fig. 7: assembled from its
// initial guess, then dragged by a point grasp along a path in 1 mm steps with one warm solve per
// step; every solve must leave the joints satisfied to 1e-10 (m, and unit vectors' dot products).

#include "optimizer/solver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "optimizer/dense_cholesky.h"
#include "optimizer/goals.h"
#include "optimizer/interaction.h"
#include "testing/alloc_counter.h"
#include "testing/contact_scenes.h"
#include "testing/fourbar.h"

namespace tangent::optimizer {
namespace {

// The servo's small dense factorization against Eigen's LLT (the one it replaced) on seeded
// random symmetric positive definite matrices of every size the servo builds and beyond, read
// from the upper triangle only, dense and with the zero blocks of a chain of bodies (7 x 7
// blocks coupled only to their neighbours: the envelope it skips); and it refuses what is not
// positive definite.
TEST(DenseCholeskyTest, MatchesEigensLltAndRefusesWhatIsNotPositiveDefinite) {
  std::srand(35);
  double worst_factor = 0.0, worst_solve = 0.0;
  for (int k = 0; k < 2 * 22; ++k) {
    const int n = k / 2 < 16 ? k / 2 + 1 : 16 + 7 * (k / 2 - 15);
    const bool chain = k % 2 == 1;
    Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, n);
    if (chain) {  // lower bidiagonal by blocks: B Bᵀ is block tridiagonal
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          if (j / 7 > i / 7 || i / 7 - j / 7 > 1) B(i, j) = 0.0;
        }
      }
    }
    Eigen::MatrixXd A = B * B.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> reference(A);
    ASSERT_EQ(reference.info(), Eigen::Success);
    A.triangularView<Eigen::StrictlyLower>().setConstant(std::nan(""));  // never read
    DenseCholesky chol;
    chol.Reserve(n);
    const long allocations_before = tangent::testing::AllocationCount();
    ASSERT_TRUE(chol.Compute(A)) << "n = " << n << (chain ? ", chain" : "");
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    Eigen::VectorXd x = b;
    chol.SolveInPlace(&x);
    EXPECT_EQ(tangent::testing::AllocationCount() - allocations_before, 0)
        << "n = " << n << (chain ? ", chain" : "");
    const Eigen::MatrixXd U = chol.factor().triangularView<Eigen::Upper>();
    const Eigen::MatrixXd U_ref = reference.matrixU();
    worst_factor = std::max(worst_factor, (U - U_ref).cwiseAbs().maxCoeff() / U_ref.norm());
    worst_solve = std::max(
        worst_solve, (x - reference.solve(b)).cwiseAbs().maxCoeff() / reference.solve(b).norm());
  }
  std::printf(
      "dense Cholesky against Eigen's LLT, n = 1 to 58, dense and chains of 7 x 7 blocks: "
      "factor %.1e, solve %.1e (relative)\n",
      worst_factor, worst_solve);
  EXPECT_LT(worst_factor, 1e-13);
  EXPECT_LT(worst_solve, 1e-10);

  DenseCholesky chol;
  chol.Reserve(3);
  Eigen::Matrix3d indefinite;
  indefinite << 2, 1, 0, 1, -1, 0, 0, 0, 1;
  EXPECT_FALSE(chol.Compute(Eigen::MatrixXd(indefinite)));
  Eigen::MatrixXd semidefinite = Eigen::MatrixXd::Ones(3, 3);
  EXPECT_FALSE(chol.Compute(semidefinite));
  Eigen::MatrixXd with_nan = Eigen::MatrixXd::Identity(3, 3);
  with_nan(1, 2) = std::nan("");
  EXPECT_FALSE(chol.Compute(with_nan));
}

TEST(SolverTest, FourBarDragKeepsJointsExactOverAThousandWarmSolves) {
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  const Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  Solver solver(p);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  const SolveStats first = solver.Solve(&q);
  ASSERT_TRUE(first.converged) << "assembly: violation " << first.max_violation;
  double worst = 0.0, worst_kkt = 0.0;
  int max_iter = 0, unconverged = 0, total_iter = 0;
  std::vector<BodyPose> poses;
  fb.mechanism.Poses(q, &poses);
  const Attachment crank_joint_ground{fb.ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}};
  const Attachment crank_joint{fb.crank, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}};
  double angle_lo = RevoluteAngle(crank_joint_ground, crank_joint, poses), angle_hi = angle_lo;
  const long allocations_before = tangent::testing::AllocationCount();
  for (int k = 1; k <= 1000; ++k) {
    SetGoalTarget(solver.data(), *goal, testing::FourBar::PathPoint(k));
    const SolveStats s = solver.Solve(&q);
    if (k % 10 == 0) {  // (Poses() reuses the vector's storage: no allocation after the first.)
      fb.mechanism.Poses(q, &poses);
      const double a = RevoluteAngle(crank_joint_ground, crank_joint, poses);
      angle_lo = std::min(angle_lo, a);
      angle_hi = std::max(angle_hi, a);
    }
    worst = std::max(worst, s.max_violation);
    worst_kkt = std::max(worst_kkt, s.kkt_residual);
    max_iter = std::max(max_iter, s.iterations);
    total_iter += s.iterations;
    unconverged += !s.converged;
  }
  const long allocations = tangent::testing::AllocationCount() - allocations_before;
  // The crank turned back and forth (±0.1 rad): the drag moved the mechanism along its one
  // degree of freedom, following the hand's x motion.
  EXPECT_GT(angle_hi - angle_lo, 0.15);
  std::printf(
      "four-bar drag, 1000 warm solves: worst violation %.1e, worst KKT %.1e, iterations "
      "mean %.2f max %d, unconverged %d, allocations %ld, crank swept %.2f rad\n",
      worst, worst_kkt, total_iter / 1000.0, max_iter, unconverged, allocations,
      angle_hi - angle_lo);
  EXPECT_LE(worst, 1e-10);
  EXPECT_EQ(unconverged, 0);
  EXPECT_EQ(allocations, 0);
}

// Two problems of the four-bar drag, each with its own goal handle, for two solvers compared
// step by step along the path.
struct TwoFourBarDrags {
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal_first, goal_second;
  const Problem first = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal_first);
  const Problem second = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal_second);
  /// Both solvers' goals to path step k.
  void Target(Solver* a, Solver* b, int k) const {
    SetGoalTarget(a->data(), *goal_first, testing::FourBar::PathPoint(k));
    SetGoalTarget(b->data(), *goal_second, testing::FourBar::PathPoint(k));
  }
};

// The finishing correction (SolverOptions::finish_violation): where the second Newton step of a
// warm solve leaves only the second-order violation of its own step (1–2.4e-10 against the
// 1e-10 tolerance, stationary to 1e-11), a back substitution with that step's factorization
// replaces the third Newton step. The same solutions as without it, two Newton steps instead of
// 2.6 on average.
TEST(SolverTest, TheFinishingCorrectionReplacesTheFourBarsThirdNewtonStep) {
  TwoFourBarDrags drags;
  SolverOptions off;
  off.finish_violation = 0.0;
  Solver with(drags.first), without(drags.second, off);
  Eigen::VectorXd q = drags.fb.mechanism.InitialCoordinates();
  ASSERT_TRUE(with.Solve(&q).converged);
  Eigen::VectorXd r = q;
  ASSERT_TRUE(without.Solve(&r).converged);
  int newton_with = 0, newton_without = 0, corrections = 0, corrections_off = 0;
  double worst = 0.0, worst_kkt = 0.0, apart = 0.0;
  const long allocations_before = tangent::testing::AllocationCount();
  for (int k = 1; k <= 300; ++k) {
    drags.Target(&with, &without, k);
    const SolveStats a = with.Solve(&q);
    const SolveStats b = without.Solve(&r);
    ASSERT_TRUE(a.converged) << "step " << k;
    ASSERT_TRUE(b.converged) << "step " << k;
    newton_with += a.iterations;
    newton_without += b.iterations;
    corrections += a.corrections;
    corrections_off += b.corrections;
    worst = std::max(worst, a.max_violation);
    worst_kkt = std::max(worst_kkt, a.kkt_residual);
    // The same path of solutions (each solve anchored at its own previous one).
    apart = std::max(apart, (q - r).cwiseAbs().maxCoeff());
  }
  const long allocations = tangent::testing::AllocationCount() - allocations_before;
  std::printf(
      "four-bar, 300 warm solves: Newton steps %.2f a solve with the finishing correction (%d "
      "corrections), %.2f without; worst violation %.1e, KKT %.1e; solutions apart %.1e\n",
      newton_with / 300.0, corrections, newton_without / 300.0, worst, worst_kkt, apart);
  EXPECT_EQ(corrections_off, 0);
  EXPECT_GT(corrections, 150);               // measured: most solves end on one
  EXPECT_LE(newton_with, 2 * 300 + 5);       // two Newton steps a solve
  EXPECT_GE(newton_without, 2 * 300 + 100);  // measured 2.6
  EXPECT_LE(worst, 1e-10);
  EXPECT_LE(worst_kkt, 1e-10);  // the correction keeps what the step reached
  EXPECT_LT(apart, 1e-9);
  EXPECT_EQ(allocations, 0);
}

// Solve(q, anchor): least astonishment from the anchor, the iterations from q. Started from a
// prediction along the path (2 x_k − x_{k−1}), it reaches the solution the plain solve reaches
// from the anchor.
TEST(SolverTest, AnAnchoredSolveFromAPredictionReachesTheSameSolution) {
  TwoFourBarDrags drags;
  Solver predicted(drags.first), plain(drags.second);
  Eigen::VectorXd q = drags.fb.mechanism.InitialCoordinates();
  ASSERT_TRUE(predicted.Solve(&q).converged);
  Eigen::VectorXd previous = q;
  double apart = 0.0;
  for (int k = 1; k <= 100; ++k) {
    drags.Target(&predicted, &plain, k);
    Eigen::VectorXd x = 2.0 * q - previous;
    for (int o = 0; o < x.size(); o += 7) x.segment<4>(o + 3).normalize();
    Eigen::VectorXd reference = q;
    previous = q;
    const SolveStats a = predicted.Solve(&x, q);
    ASSERT_TRUE(plain.Solve(&reference).converged);
    ASSERT_TRUE(a.converged) << "step " << k;
    apart = std::max(apart, (x - reference).cwiseAbs().maxCoeff());
    q = x;
  }
  EXPECT_LT(apart, 1e-8);
  // An anchor of the wrong size or not finite is invalid input: q as it came.
  Eigen::VectorXd x = q;
  EXPECT_TRUE(predicted.Solve(&x, Eigen::VectorXd::Zero(3)).invalid_input);
  EXPECT_EQ(x, q);
  Eigen::VectorXd bad = q;
  bad[0] = std::nan("");
  EXPECT_TRUE(predicted.Solve(&x, bad).invalid_input);
  EXPECT_EQ(x, q);
}

TEST(SolverTest, FourBarDraggedThroughAFloatingSurfaceContactKeepsItExact) {
  testing::FloatingGraspFourBar fb;
  const Eigen::Vector4d seed = fb.RestSeed();
  std::shared_ptr<PositionGoalTerm> goal;
  std::shared_ptr<SurfaceContactTerm> contact;
  const Problem p = fb.MakeProblem(&goal, &contact, seed);
  Solver solver(p);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  const SolveStats first = solver.Solve(&q);
  ASSERT_TRUE(first.converged) << "assembly: violation " << first.max_violation << " seed "
                               << seed.transpose() << " u "
                               << solver.data().Of(*contact).extremum().u.transpose() << " beta "
                               << solver.data().Of(*contact).extremum().beta << " status "
                               << contact::ToString(solver.data().Of(*contact).extremum().status);
  double worst = 0.0, worst_beta = 0.0, worst_hand = 0.0;
  int total_iter = 0, max_iter = 0, unconverged = 0;
  const Eigen::Vector3d coupler_start = q.segment<3>(p.mechanism().offset(fb.coupler));
  double coupler_travel = 0.0;
  const long allocations_before = tangent::testing::AllocationCount();
  for (int k = 1; k <= 1000; ++k) {
    SetGoalTarget(solver.data(), *goal, fb.HandPoint(k));
    const SolveStats s = solver.Solve(&q);
    worst = std::max(worst, s.max_violation);
    worst_beta = std::max(worst_beta, std::abs(solver.data().Of(*contact).extremum().beta));
    unconverged += !s.converged;
    total_iter += s.iterations;
    max_iter = std::max(max_iter, s.iterations);
    ASSERT_EQ(solver.data().Of(*contact).extremum().status, contact::ExtremalStatus::kConverged)
        << "step " << k << " u " << solver.data().Of(*contact).extremum().u.transpose() << " beta "
        << solver.data().Of(*contact).extremum().beta << " rcond "
        << solver.data().Of(*contact).extremum().rcond;
    const Eigen::Vector3d tip = q.segment<3>(p.mechanism().offset(fb.finger));
    worst_hand = std::max(worst_hand, (tip - fb.HandPoint(k)).norm());
    coupler_travel = std::max(
        coupler_travel, (q.segment<3>(p.mechanism().offset(fb.coupler)) - coupler_start).norm());
  }
  const long allocations = tangent::testing::AllocationCount() - allocations_before;
  std::printf(
      "floating-grasp four-bar, 1000 warm solves: worst violation %.1e (beta %.1e), iterations "
      "mean %.2f max %d, unconverged %d, allocations %ld, hand-tip gap max %.1e m, coupler "
      "moved %.1f mm\n",
      worst, worst_beta, total_iter / 1000.0, max_iter, unconverged, allocations, worst_hand,
      1e3 * coupler_travel);
  EXPECT_LE(worst, 1e-10);
  EXPECT_LE(worst_beta, 1e-10);
  EXPECT_EQ(unconverged, 0);
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(coupler_travel, 0.002);  // the contact drove the mechanism
}

// Model / Data: the Problem and its terms are shared and never changed by a solve; each solver
// owns its data (the goal's target, the floating contact's tracked parameters). Four threads
// drag the same problem along the same path at once, each through its own solver, and get the
// serial answers bit for bit; a thread on a different path does not disturb them.
TEST(SolverTest, OneProblemSolvedOnSeveralThreadsAtOnceGivesTheSerialAnswers) {
  testing::FloatingGraspFourBar fb;
  const Eigen::Vector4d seed = fb.RestSeed();
  std::shared_ptr<PositionGoalTerm> goal;
  std::shared_ptr<SurfaceContactTerm> contact;
  const Problem p = fb.MakeProblem(&goal, &contact, seed);
  constexpr int kSteps = 300;
  // One drag along the hand path (reverse: the other direction), from scratch.
  auto drag = [&](bool reverse) {
    Solver solver(p);
    Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
    std::vector<Eigen::VectorXd> path;
    std::vector<double> beta;
    solver.Solve(&q);
    for (int k = 1; k <= kSteps; ++k) {
      SetGoalTarget(solver.data(), *goal, fb.HandPoint(reverse ? -k : k));
      solver.Solve(&q);
      path.push_back(q);
      beta.push_back(solver.data().Of(*contact).extremum().beta);
    }
    return std::make_pair(path, beta);
  };
  const auto serial = drag(false);
  constexpr int kThreads = 4;
  std::vector<std::pair<std::vector<Eigen::VectorXd>, std::vector<double>>> results(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) threads.emplace_back([&, t] { results[t] = drag(false); });
  std::thread other([&] { drag(true); });
  for (std::thread& t : threads) t.join();
  other.join();
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_EQ(results[t].first.size(), serial.first.size());
    for (int k = 0; k < kSteps; ++k) {
      ASSERT_EQ((results[t].first[k] - serial.first[k]).cwiseAbs().maxCoeff(), 0.0)
          << "thread " << t << " step " << k;
      ASSERT_EQ(results[t].second[k], serial.second[k]) << "thread " << t << " step " << k;
    }
  }
  // The problem's own goal is untouched: a new solver starts from the constructed target.
  Solver fresh(p);
  EXPECT_EQ(fresh.data().Of(*goal).target, goal->initial_target());
}

TEST(SolverTest, SolveForGoalSubdividesALargeMoveAndPullToGoalFollowsTheLine) {
  // A 4 cm jump of the grasp target with a budget of 6 iterations per solve: one solve cannot
  // get there (the nearest configuration is across the crank's swing), so solve-for-goal halves
  // the move until solves converge and then walks on; pull-to-goal takes 20 subgoals.
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  const Eigen::Vector3d from = testing::FourBar::PathPoint(0);
  const Eigen::Vector3d to = from + Eigen::Vector3d(0.04, 0.0, -0.01);
  const Problem p = fb.MakeProblem(from, &goal);
  SolverOptions opt;
  opt.max_iterations = 6;
  Solver solver(p, opt);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  Solver assemble(p);
  ASSERT_TRUE(assemble.Solve(&q).converged);
  const Eigen::VectorXd q0 = q;
  {
    Eigen::VectorXd direct = q0;
    SetGoalTarget(solver.data(), *goal, to);
    EXPECT_FALSE(solver.Solve(&direct).converged);  // one solve is not enough
  }
  Solver fresh(p, opt);
  const ModeStats st = SolveForGoal(
      &fresh, &q, [&](double s) { SetGoalTarget(fresh.data(), *goal, from + s * (to - from)); });
  EXPECT_TRUE(st.reached);
  EXPECT_GT(st.subdivisions, 0);
  EXPECT_LE(st.last.max_violation, 1e-10);
  Solver puller(p, opt);
  Eigen::VectorXd q_pull = q0;
  const ModeStats pull = PullToGoal(
      &puller, &q_pull,
      [&](double s) { SetGoalTarget(puller.data(), *goal, from + s * (to - from)); }, 20);
  EXPECT_TRUE(pull.reached);
  EXPECT_EQ(pull.solves, 20);
  // Both end at the configuration nearest the target along the coupler curve, once least
  // astonishment (whose reference is each path's last step) has settled: 3 more solves each.
  for (int k = 0; k < 3; ++k) {
    fresh.Solve(&q);
    puller.Solve(&q_pull);
  }
  // (To the solves' stopping test: KKT 1e-8 leaves ~2e-8 in coordinates along the free motion.)
  EXPECT_LT((q_pull - q).cwiseAbs().maxCoeff(), 1e-7);
  std::printf("solve for goal: %d solves, %d subdivisions; pull to goal: %d solves\n", st.solves,
              st.subdivisions, pull.solves);
}

TEST(SolverTest, ReducedHessianTellsMinimaFromSaddles) {
  // A pendulum (revolute about z at the origin, tip 0.1 m out along x) and a goal pulling the
  // tip towards a point: placed on the far side from the goal the configuration is stationary
  // but a maximum of the distance along the free rotation (reduced Hessian negative); on the
  // near side it is a minimum.
  Mechanism m;
  Body g{"ground"};
  g.fixed = true;
  const int ground = m.AddBody(g);
  const int link = m.AddBody(Body{"link"});
  for (double side : {-1.0, 1.0}) {
    Problem p(m);
    p.AddEquality(RevoluteJoint({ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}},
                                {link, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}));
    p.AddObjective(PositionGoal({link, {0.1, 0, 0}}, {side, 0, 0}), 1.0);
    p.set_least_astonishment(0.0);
    SolverOptions opt;
    opt.second_order_check = true;
    Solver solver(p, opt);
    Eigen::VectorXd q = m.InitialCoordinates();
    const SolveStats s = solver.Solve(&q);
    ASSERT_TRUE(s.converged);
    ASSERT_TRUE(s.reduced_hessian_checked);
    EXPECT_EQ(s.reduced_hessian_positive_definite, side > 0) << side;
    EXPECT_EQ(s.reduced_hessian_min_eigenvalue > 0, side > 0) << s.reduced_hessian_min_eigenvalue;
  }
  // The four-bar's dragged configurations are minima.
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  const Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  SolverOptions opt;
  opt.second_order_check = true;
  Solver solver(p, opt);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  for (int k = 0; k <= 50; k += 10) {
    SetGoalTarget(solver.data(), *goal, testing::FourBar::PathPoint(k));
    const SolveStats s = solver.Solve(&q);
    EXPECT_TRUE(s.reduced_hessian_positive_definite)
        << k << " " << s.reduced_hessian_min_eigenvalue;
  }
}

TEST(SolverTest, ABudgetReturnsTheBestIterateWithItsOwnStatistics) {
  // Two iterations for a 4 cm jump: not converged; the configuration returned is the best one
  // seen, finite, and the statistics describe it (checked by evaluating it independently).
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  const Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  Solver(p).Solve(&q);
  for (int budget : {1, 2, 3}) {
    SolverOptions opt;
    opt.max_iterations = budget;
    Solver solver(p, opt);
    Eigen::VectorXd qb = q;
    SetGoalTarget(solver.data(), *goal,
                  testing::FourBar::PathPoint(0) + Eigen::Vector3d(0.04, 0, -0.01));
    const SolveStats s = solver.Solve(&qb);
    EXPECT_FALSE(s.converged);
    ASSERT_TRUE(qb.allFinite());
    ProblemEvaluator ev(p);
    ev.Evaluate(qb);
    EXPECT_DOUBLE_EQ(s.max_violation, ev.c_e().cwiseAbs().maxCoeff()) << budget;
  }
}

TEST(SolverTest, WarmSolveReachesTheColdOptimum) {
  // Without least astonishment the optimum is where the grasp is closest to the goal on the
  // mechanism's one-dimensional configuration curve; warm and cold solves must agree there.
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  p.set_least_astonishment(0.0);
  SolverOptions opt;
  opt.kkt_tolerance = 1e-12;
  Solver warm(p, opt);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  warm.Solve(&q);
  for (int k = 1; k <= 120; ++k) {
    SetGoalTarget(warm.data(), *goal, testing::FourBar::PathPoint(k));
    warm.Solve(&q);
  }
  Solver cold(p, opt);
  SetGoalTarget(cold.data(), *goal, testing::FourBar::PathPoint(120));
  Eigen::VectorXd q_cold = fb.mechanism.InitialCoordinates();
  const SolveStats s = cold.Solve(&q_cold);
  ASSERT_TRUE(s.converged);
  std::vector<BodyPose> pw, pc;
  fb.mechanism.Poses(q, &pw);
  fb.mechanism.Poses(q_cold, &pc);
  const Eigen::Vector3d gw = pw[fb.coupler].Point(fb.grasp.point),
                        gc = pc[fb.coupler].Point(fb.grasp.point);
  EXPECT_LT((gw - gc).norm(), 1e-8);
}

TEST(SolverTest, ConflictingGoalsGiveTheWeightedCompromise) {
  // Two position goals on one point, 10 cm apart, weights 1 and 3: the point settles at the
  // weighted mean (a free body: no constraint besides |Q| = 1), never a blow-up.
  Mechanism m;
  const int b = m.AddBody(Body{"free"});
  Problem p(m);
  p.set_least_astonishment(0.0);
  const Attachment at{b, {0.02, 0, 0}};
  p.AddObjective(PositionGoal(at, {0, 0, 0}), 1.0);
  p.AddObjective(PositionGoal(at, {0.1, 0, 0}), 3.0);
  Solver s(p);
  Eigen::VectorXd q = m.InitialCoordinates();
  const SolveStats st = s.Solve(&q);
  std::vector<BodyPose> poses;
  m.Poses(q, &poses);
  EXPECT_TRUE(st.converged);
  EXPECT_LT((poses[b].Point(at.point) - Eigen::Vector3d(0.075, 0, 0)).norm(), 1e-9);
}

TEST(SolverTest, RedundantClosureStillConverges) {
  // The four-bar with its spherical joint listed twice: a rank-deficient constraint Jacobian.
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  Problem p = fb.MakeProblem(testing::FourBar::PathPoint(10), &goal);
  p.AddEquality(SphericalJoint({fb.coupler, {0.3, -0.1, 0.15}}, {fb.rocker, {0, 0, 0.15}}));
  Solver s(p);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  const SolveStats st = s.Solve(&q);
  EXPECT_TRUE(st.converged);
  EXPECT_LE(st.max_violation, 1e-10);
}

TEST(SolverTest, JointLimitsHoldAsInequalities) {
  // Drag the four-bar's crank against a limit of ±0.2 rad: the limit holds, the goal is missed.
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  const Attachment ground{fb.ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}};
  const Attachment crank{fb.crank, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}};
  p.AddInequality(RevoluteLimits(ground, crank, -0.2, 0.2));
  Solver s(p);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  s.Solve(&q);
  std::vector<BodyPose> poses;
  for (int k = 1; k <= 300; ++k) {
    SetGoalTarget(s.data(), *goal, testing::FourBar::PathPoint(k));
    const SolveStats st = s.Solve(&q);
    EXPECT_LE(st.max_violation, 1e-10) << k;
    fb.mechanism.Poses(q, &poses);
    const double a = RevoluteAngle(ground, crank, poses);
    EXPECT_GE(a, -0.2 - 1e-10);
    EXPECT_LE(a, 0.2 + 1e-10);
  }
}

// A probe pressed onto a ball by a goal inside it and dragged round the equator: a loaded
// contact on a curved surface as a warm-started inequality (the servo loop's situation). After
// each tangential step the exact constraint is positive by the step's second order while its
// multiplier is not, so the inequality's active set must come from the step, not from the
// current point (PHR's λ − μc > 0 drops it and the step runs into the ball).
TEST(SolverTest, ALoadedContactOnACurvedSurfaceStaysActiveWhileDragged) {
  constexpr double radius = 0.01;
  const nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), radius);
  auto run = [&](int active_set_passes, double* mean_iterations, int* budget_hits,
                 double* worst_violation, double* worst_complementarity, double* load) {
    Mechanism m;
    const int fixed = m.AddBody(Body{"ball", true});
    Body probe_body{"probe"};
    probe_body.pose << radius, 0, 0, 1, 0, 0, 0;
    const int probe = m.AddBody(probe_body);
    Problem p(m);
    const Attachment tip{probe, {0, 0, 0}};
    auto goal = MakePositionGoal(tip, {0.6 * radius, 0, 0});
    p.AddObjective(goal, 1.0);
    p.AddInequality(MakePointOnSurface(tip, fixed, &ball, {0.0, 0.5}));
    SolverOptions o;
    o.max_iterations = 10;
    o.max_active_set_passes = active_set_passes;
    Solver s(p, o);
    Eigen::VectorXd q = m.InitialCoordinates();
    s.Solve(&q);
    int iterations = 0;
    *budget_hits = 0;
    *worst_violation = *worst_complementarity = 0.0;
    constexpr int kSteps = 400;
    for (int k = 1; k <= kSteps; ++k) {  // 0.02 rad (0.2 mm along the surface) per step
      const double a = 0.02 * k;
      SetGoalTarget(s.data(), *goal, 0.6 * radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
      const SolveStats st = s.Solve(&q);
      iterations += st.iterations;
      *budget_hits += !st.converged;
      *worst_violation = std::max(*worst_violation, st.max_violation);
      *worst_complementarity = std::max(*worst_complementarity, st.complementarity);
    }
    *mean_iterations = static_cast<double>(iterations) / kSteps;
    *load = s.inequality_multipliers()[0];
  };
  double mean = 0.0, worst = 0.0, comp = 0.0, load = 0.0;
  int hits = 0;
  run(1, &mean, &hits, &worst, &comp, &load);  // the guess alone
  std::printf(
      "probe on a ball, active set guessed from the point: iterations mean %.2f, "
      "%d of 400 solves at the budget, worst violation %.1e\n",
      mean, hits, worst);
  const int guess_hits = hits;
  run(SolverOptions{}.max_active_set_passes, &mean, &hits, &worst, &comp, &load);
  std::printf(
      "probe on a ball, active set from the step: iterations mean %.2f, %d at the "
      "budget, worst violation %.1e, complementarity %.1e\n",
      mean, hits, worst, comp);
  EXPECT_EQ(hits, 0);
  EXPECT_LE(mean, 3.0);
  EXPECT_LE(worst, 1e-10);
  EXPECT_LE(comp, 1e-10);
  // The contact carries the goal's pull, weight x 0.4 radius (least astonishment aside).
  EXPECT_NEAR(load, 0.4 * radius, 1e-6 * radius);
  EXPECT_GT(guess_hits, 0);  // the failure this guards against, reproduced
}

// A probe pressed onto a ball by a pull from straight behind the ball: the contact's curvature
// (the ball's 1/R, times a load of three radii's pull) outweighs the pull's along the ball, so
// the Newton matrix is not positive definite, and the stationary point is a saddle (sliding
// round the ball would bring the probe nearer the target). The solve is Newton on the KKT
// conditions: from a start a little off the axis it converges to that point in a few exact
// (indefinite) steps, allocating nothing. Damping the matrix until it was positive definite
// instead shortened the steps until the iteration cap.
// A probe on a fixed ball, 1.1° off the axis, pulled toward a point two radii behind the ball.
struct ProbeOnABall {
  static constexpr double radius = 0.01;
  nurbs::NurbsSurface ball = nurbs::MakeSphere(Eigen::Vector3d::Zero(), radius);
  std::shared_ptr<PositionGoalTerm> goal;
  std::unique_ptr<Problem> problem;
  ProbeOnABall() {
    Mechanism m;
    const int fixed = m.AddBody(Body{"ball", true});
    Body probe_body{"probe"};
    probe_body.pose << radius, 0.02 * radius, 0, 1, 0, 0, 0;  // on the ball, 1.1° off the axis
    const int probe = m.AddBody(probe_body);
    problem = std::make_unique<Problem>(m);
    const Attachment tip{probe, {0, 0, 0}};
    goal = MakePositionGoal(tip, {-2.0 * radius, 0, 0});
    problem->AddObjective(goal, 1.0);
    problem->AddInequality(MakePointOnSurface(tip, fixed, &ball, {0.0, 0.5}));
    problem->set_least_astonishment(0.0);
  }
};

TEST(SolverTest, AnIndefiniteNewtonMatrixGetsItsExactStep) {
  const ProbeOnABall b;
  constexpr double radius = ProbeOnABall::radius;
  const Problem& p = *b.problem;
  const Mechanism& m = p.mechanism();
  const auto& goal = b.goal;
  SolverOptions o;
  o.max_iterations = 10;
  o.second_order_check = true;
  Solver s(p, o);
  Eigen::VectorXd q = m.InitialCoordinates();
  const long allocations_before = tangent::testing::AllocationCount();
  SolveStats st = s.Solve(&q);
  const long allocations = tangent::testing::AllocationCount() - allocations_before;
  ASSERT_TRUE(st.converged) << "iterations " << st.iterations << ", kkt " << st.kkt_residual;
  EXPECT_GT(st.indefinite_steps, 0);
  EXPECT_LE(st.iterations, 6);
  EXPECT_EQ(allocations, 0);
  // On the axis, pressed with the pull's whole force (three radii at weight 1), at a saddle.
  EXPECT_NEAR(q[0], radius, 1e-10);
  EXPECT_NEAR(q.segment<2>(1).norm(), 0.0, 1e-8);
  EXPECT_NEAR(s.inequality_multipliers()[0], 3.0 * radius, 1e-9);
  ASSERT_TRUE(st.reduced_hessian_checked);
  EXPECT_FALSE(st.reduced_hessian_positive_definite);
  // Pulled to a point off the ball instead, the probe leaves it and settles there, where the
  // matrix is positive definite again: no indefinite step.
  SetGoalTarget(s.data(), *goal, {2.0 * radius, 2.0 * radius, 0});
  for (int k = 0; k < 3; ++k) st = s.Solve(&q);
  EXPECT_TRUE(st.converged);
  EXPECT_EQ(st.indefinite_steps, 0);
  EXPECT_NEAR((q.head<3>() - Eigen::Vector3d(2.0, 2.0, 0.0) * radius).norm(), 0.0, 1e-9);
}

// SolverOptions::indefinite_floor: an indefinite matrix's step along an eigenvector whose
// eigenvalue is smaller in magnitude than the floor (times the objective's scale, 1 here) is
// damped to it. The probe of the test above, pressed onto the ball by a pull from behind it,
// stands at a saddle along the ball (the Lagrangian's curvature there −2): the exact step, or
// one under a floor of 1, converges onto it in 3 steps; a floor of 10 damps that step to a
// fifth and turns it downhill, and the solve no longer finds the saddle.
TEST(SolverTest, AnIndefiniteStepIsDampedToItsFloorOnlyBelowIt) {
  constexpr double radius = ProbeOnABall::radius;
  auto solve = [&](double floor, Eigen::VectorXd* q) {
    const ProbeOnABall b;
    SolverOptions o;
    o.max_iterations = 8;
    o.indefinite_floor = floor;
    Solver s(*b.problem, o);
    *q = b.problem->mechanism().InitialCoordinates();
    return s.Solve(q);
  };
  Eigen::VectorXd exact, below, above;
  const SolveStats st_exact = solve(0.0, &exact);
  const SolveStats st_below = solve(1.0, &below);
  const SolveStats st_above = solve(10.0, &above);
  ASSERT_TRUE(st_exact.converged);
  EXPECT_GT(st_exact.indefinite_steps, 0);
  ASSERT_TRUE(st_below.converged);
  EXPECT_EQ(st_below.iterations, st_exact.iterations);
  EXPECT_LT((below - exact).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(exact[1], 0.0, 1e-8);
  EXPECT_FALSE(st_above.converged);
  EXPECT_GT(st_above.indefinite_steps, 0);
  EXPECT_GT(std::abs(above[1]), 0.02 * radius) << "not on the axis";
}

// Issue 13: a non-finite input gets a defined status and never poisons the next solve. Before,
// the residuals' maxCoeff skipped a NaN (a NaN configuration returned "converged" after 0
// iterations), and one NaN goal turned the multipliers into NaN for every later solve.
TEST(SolverTest, NonFiniteInputIsRejectedAndNeverPoisonsTheNextSolve) {
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  const Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  Solver solver(p);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  ASSERT_TRUE(solver.Solve(&q).converged);
  const Eigen::VectorXd good = q;
  const Eigen::VectorXd lambda = solver.equality_multipliers();
  // A NaN coordinate (anywhere, not only first).
  for (Eigen::Index k : {Eigen::Index{0}, q.size() / 2, q.size() - 1}) {
    Eigen::VectorXd bad = good;
    bad[k] = std::numeric_limits<double>::quiet_NaN();
    const SolveStats s = solver.Solve(&bad);
    EXPECT_FALSE(s.converged) << k;
    EXPECT_TRUE(s.invalid_input) << k;
    EXPECT_EQ(s.iterations, 0);
    EXPECT_TRUE(std::isinf(s.max_violation));
    EXPECT_EQ(solver.equality_multipliers(), lambda);
  }
  // A NaN or infinite goal target: rejected, q and the multipliers untouched, and the next
  // valid solves as fast as before.
  for (double bad_target : {std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::infinity(), -1e308 * 10}) {
    SetGoalTarget(solver.data(), *goal, Eigen::Vector3d(0.1, bad_target, 0.0));
    Eigen::VectorXd x = good;
    const SolveStats s = solver.Solve(&x);
    EXPECT_FALSE(s.converged);
    EXPECT_TRUE(s.invalid_input);
    EXPECT_EQ(x, good);
    EXPECT_TRUE(solver.equality_multipliers().allFinite());
    EXPECT_TRUE(solver.inequality_multipliers().allFinite());
    SetGoalTarget(solver.data(), *goal, testing::FourBar::PathPoint(1));
    const SolveStats next = solver.Solve(&x);
    EXPECT_TRUE(next.converged);
    EXPECT_LE(next.iterations, 6);
    EXPECT_TRUE(x.allFinite());
    x = good;
    SetGoalTarget(solver.data(), *goal, testing::FourBar::PathPoint(0));
    ASSERT_TRUE(solver.Solve(&x).converged);
  }
}

// A weld started 0.3 rad short of its flipped configurations (the part's axis reversed, a half
// turn about the axis, or both) used to converge there: the "axes parallel" rows vanish for
// antiparallel axes too, and the weld's reference row for a half turn. Now no flipped
// configuration is a solution: the solve must not end there. (From that far out the cold solve
// does not reach the weld within its 60 iterations either: the mapped rows are flat at 90°,
// where sin θ peaks; docs/optimizer.md says so.)
TEST(SolverTest, AWeldStartedNearAFlipDoesNotConvergeThere) {
  Mechanism m;
  Body g{"ground"};
  g.fixed = true;
  const int ground = m.AddBody(g);
  const int part = m.AddBody(Body{"part"});
  const Eigen::Vector3d axis(0, 0, 1), ref(1, 0, 0);
  for (const Eigen::Vector3d& flip_about : {ref, axis, Eigen::Vector3d(axis.cross(ref))}) {
    Problem p(m);
    p.AddEquality(FixedJoint({ground, {0, 0, 0}, axis, ref}, {part, {0, 0, 0}, axis, ref}));
    Solver solver(p);
    Eigen::VectorXd q = m.InitialCoordinates();
    const Eigen::Quaterniond flip(Eigen::AngleAxisd(std::numbers::pi, flip_about));
    const Eigen::Quaterniond start(Eigen::AngleAxisd(std::numbers::pi - 0.3, flip_about));
    q.segment<4>(3) << start.w(), start.x(), start.y(), start.z();
    const SolveStats s = solver.Solve(&q);
    const Eigen::Quaterniond end(q[3], q[4], q[5], q[6]);
    std::printf(
        "weld from %.2f rad about (%g %g %g): %d iterations, %s, violation %.1e, %.2f rad "
        "from the flip\n",
        std::numbers::pi - 0.3, flip_about.x(), flip_about.y(), flip_about.z(), s.iterations,
        s.converged ? "converged" : "not converged", s.max_violation, end.angularDistance(flip));
    EXPECT_GE(end.angularDistance(flip), 0.29);
    EXPECT_FALSE(s.converged && s.max_violation < 1e-6 && end.angularDistance(flip) < 0.29);
    EXPECT_GT(s.max_violation, 0.1);  // not a solution
  }
}

}  // namespace
}  // namespace tangent::optimizer
