// Offline design solves (SolverOptions::design): a three-link arm whose tip must stay on a plane
// maximizes its dexterity √det(JJᵀ). Checked against IPOPT from the same starts (same optimum),
// and the multiplier of the plane constraint against the change of the optimum when the plane
// is moved (the sensitivity of the optimal objective to the constraint's right-hand side).

#include <gtest/gtest.h>

#include <cstdio>

#include "optimizer/dexterity.h"
#include "optimizer/goals.h"
#include "optimizer/solver.h"
#include "testing/ipopt_problem.h"
#include "testing/three_link.h"

namespace tangent::optimizer {
namespace {

using testing::Bent;
using testing::ThreeLink;

// The arm's dexterity (all three joints chosen) maximized with the tip on the plane z = height.
struct ArmOnPlane {
  ThreeLink arm;
  Problem joints_only;  // defines the dexterity's mechanism (3 DOF)
  Problem problem;
  std::shared_ptr<Dexterity> dexterity;
  explicit ArmOnPlane(double height, double weight = 1.0)
      : joints_only(arm.MakeProblem()), problem(arm.MakeProblem()) {
    problem.AddEquality(
        PlaneGoal(arm.tip, Eigen::Vector3d(0, 0, height), Eigen::Vector3d::UnitZ()));
    dexterity = std::make_shared<Dexterity>(joints_only, arm.tip, arm.joints);
    problem.AddDesignObjective(MakeDexterityObjective(dexterity, DexterityMeasure::kDexterity),
                               weight);
    problem.set_least_astonishment(0.0);
  }
  // The plane's row among the equalities: after the three joints (5 rows each) and the three
  // unit quaternions.
  int PlaneRow() const { return problem.equalities().back().row; }
};

SolverOptions DesignOptions() {
  SolverOptions o;
  o.design.enabled = true;
  o.max_iterations = 300;
  o.constraint_tolerance = 1e-12;
  return o;
}

const Eigen::Vector3d kStarts[] = {
    {0.3, 0.7, -0.4}, {-1.0, 1.2, 0.9}, {2.0, 0.4, 1.5}, {0.0, -0.8, -1.1}};

TEST(DesignSolveTest, ArmOnAPlaneReachesIpoptsOptimumFromEveryStart) {
  ArmOnPlane s(0.2);
  testing::IpoptSolver ipopt(s.problem);
  for (const Eigen::Vector3d& angles : kStarts) {
    const Eigen::VectorXd q0 = Bent(s.arm, angles);
    Solver solver(s.problem, DesignOptions());
    Eigen::VectorXd q = q0;
    const SolveStats st = solver.Solve(&q);
    const testing::IpoptResult ref = ipopt.Solve(q0);
    ASSERT_TRUE(ref.solved) << angles.transpose();
    const double ours = s.dexterity->Evaluate(q, false).dexterity;
    const double theirs = s.dexterity->Evaluate(ref.q, false).dexterity;
    std::printf(
        "start (%5.2f %5.2f %5.2f): ours %.10f in %d iterations (violation %.1e), "
        "IPOPT %.10f in %d\n",
        angles[0], angles[1], angles[2], ours, st.iterations, st.max_violation, theirs,
        ref.iterations);
    EXPECT_TRUE(st.converged) << angles.transpose();
    EXPECT_LE(st.max_violation, 1e-12);
    EXPECT_NEAR(ours, theirs, 1e-6 * theirs) << angles.transpose();
    // The optimum is a family (the turntable angle is free); the elbow and wrist angles and the
    // tip height are not: compare them up to the elbow-up / elbow-down mirror.
    std::vector<BodyPose> a, b;
    s.arm.mech.Poses(q, &a);
    s.arm.mech.Poses(ref.q, &b);
    const double elbow_a = RevoluteAngle(s.arm.joints[1].first, s.arm.joints[1].second, a);
    const double elbow_b = RevoluteAngle(s.arm.joints[1].first, s.arm.joints[1].second, b);
    const double wrist_a = RevoluteAngle(s.arm.joints[2].first, s.arm.joints[2].second, a);
    const double wrist_b = RevoluteAngle(s.arm.joints[2].first, s.arm.joints[2].second, b);
    EXPECT_NEAR(std::abs(wrist_a), std::abs(wrist_b), 1e-6);
    (void)elbow_a;
    (void)elbow_b;
  }
}

TEST(DesignSolveTest, SmallWeightsAreSolvedToTheSameOptimum) {
  // The relative KKT tolerance: a weight of 1e-5 on the objective must not stop the solve at a
  // point whose (small) gradient meets an absolute tolerance.
  ArmOnPlane heavy(0.2, 1.0), light(0.2, 1e-5);
  Eigen::VectorXd q1 = Bent(heavy.arm), q2 = Bent(light.arm);
  Solver(heavy.problem, DesignOptions()).Solve(&q1);
  const SolveStats st = Solver(light.problem, DesignOptions()).Solve(&q2);
  EXPECT_TRUE(st.converged);
  EXPECT_NEAR(light.dexterity->Evaluate(q2, false).dexterity,
              heavy.dexterity->Evaluate(q1, false).dexterity, 1e-8);
}

TEST(DesignSolveTest, PlaneMultiplierIsTheOptimumsSensitivityToTheHeight) {
  // E = −w f, and ∇E = Jᵀλ at the optimum: moving the plane's right-hand side by ε (the plane
  // up by ε) changes the optimal E by λ ε, the optimal dexterity by −λ ε / w.
  const double h = 0.2, eps = 1e-4;
  ArmOnPlane s(h);
  Eigen::VectorXd q = Bent(s.arm);
  Solver solver(s.problem, DesignOptions());
  ASSERT_TRUE(solver.Solve(&q).converged);
  const double lambda = solver.equality_multipliers()[s.PlaneRow()];
  // n·(P − origin) = b is the plane at height h + b.
  auto optimum = [&](double height) {
    ArmOnPlane moved(height);
    Eigen::VectorXd qm = q;
    Solver sm(moved.problem, DesignOptions());
    EXPECT_TRUE(sm.Solve(&qm).converged);
    return moved.dexterity->Evaluate(qm, false).dexterity;
  };
  const double fd = (optimum(h + eps) - optimum(h - eps)) / (2 * eps);
  const double sensitivity = -lambda;
  std::printf("d(dexterity*)/dh: multiplier %.9f, re-solved central difference %.9f\n", sensitivity,
              fd);
  EXPECT_NEAR(sensitivity, fd, 1e-4 * std::abs(fd) + 1e-9);
}

}  // namespace
}  // namespace tangent::optimizer
