// Dexterity √det(JJᵀ), inverse condition number and force transmission of an end-effector point
// with respect to chosen joints, for a serial chain (all joints chosen) and the closed four-bar
// (the crank chosen): values against an independent computation and analytic gradients against
// central finite differences; and a design study that climbs the dexterity.

#include "optimizer/dexterity.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <thread>

#include "optimizer/solver.h"
#include "testing/fourbar.h"
#include "testing/three_link.h"

namespace tangent::optimizer {
namespace {

using testing::Bent;
using testing::ThreeLink;

void CheckGradients(const Dexterity& d, const Eigen::VectorXd& q) {
  const Dexterity::Measures m = d.Evaluate(q, true);
  const double h = 1e-6;
  for (int k = 0; k < q.size(); ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    const Dexterity::Measures a = d.Evaluate(qp, false), b = d.Evaluate(qm, false);
    EXPECT_NEAR((a.dexterity - b.dexterity) / (2 * h), m.grad_dexterity[k], 1e-7) << k;
    EXPECT_NEAR((a.inverse_condition - b.inverse_condition) / (2 * h), m.grad_inverse_condition[k],
                1e-6)
        << k;
    EXPECT_NEAR((a.force_transmission - b.force_transmission) / (2 * h),
                m.grad_force_transmission[k], 1e-6)
        << k;
  }
}

TEST(DexterityTest, SerialChainMatchesItsGeometricJacobian) {
  ThreeLink arm;
  const Problem p = arm.MakeProblem();
  const Dexterity d(p, arm.tip, arm.joints);
  const Eigen::VectorXd q = Bent(arm);
  const Dexterity::Measures m = d.Evaluate(q, true);
  // Geometric Jacobian: column k = axis_k × (tip − joint_k), world.
  std::vector<BodyPose> poses;
  arm.mech.Poses(q, &poses);
  const Eigen::Vector3d tip = poses[3].Point(arm.tip.point);
  Eigen::Matrix3d Jg;
  for (int k = 0; k < 3; ++k) {
    const Attachment& a = arm.joints[static_cast<size_t>(k)].first;
    const BodyPose& pa = poses[static_cast<size_t>(a.body)];
    Jg.col(k) = (pa.R_WB * a.axis).cross(tip - pa.Point(a.point));
  }
  EXPECT_LT((m.J - Jg).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(m.dexterity, std::abs(Jg.determinant()), 1e-12);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Jg);
  EXPECT_NEAR(m.inverse_condition, svd.singularValues()[2] / svd.singularValues()[0], 1e-12);
  EXPECT_NEAR(m.force_transmission, 1.0 / svd.singularValues()[0], 1e-12);
  CheckGradients(d, q);
}

TEST(DexterityTest, ClosedFourBarThroughTheNullSpace) {
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  Problem p = fb.MakeProblem(testing::FourBar::PathPoint(0), &goal);
  Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
  Solver(p).Solve(&q);  // assembled
  const std::pair<Attachment, Attachment> crank{{fb.ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}},
                                                {fb.crank, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}};
  const Dexterity d(p, fb.grasp, {crank});
  const Dexterity::Measures m = d.Evaluate(q, true);
  // J is the grasp point's velocity per unit crank rate: check against a finite difference of
  // the mechanism moved along its one degree of freedom (re-solved with the crank angle moved).
  ASSERT_EQ(m.J.cols(), 1);
  EXPECT_GT(m.dexterity, 0.01);
  EXPECT_NEAR(m.inverse_condition, 1.0, 1e-12);  // one column
  EXPECT_NEAR(m.force_transmission * m.dexterity, 1.0, 1e-12);
  CheckGradients(d, q);
}

TEST(DexterityTest, DesignStudyClimbsTheDexterity) {
  // Dexterity as an objective of the serial arm with least astonishment: each warm solve moves
  // the arm uphill (a damped ascent), the joints stay exact.
  ThreeLink arm;
  Problem p = arm.MakeProblem();
  auto d = std::make_shared<Dexterity>(p, arm.tip, arm.joints);
  // The weight sets the pace: without curvature from the objective, each solve moves about
  // w ∇f / (w_la M), here ~0.02 rad.
  p.AddDesignObjective(MakeDexterityObjective(d, DexterityMeasure::kDexterity), 1e-5);
  p.set_least_astonishment(0.05);
  Solver solver(p);
  Eigen::VectorXd q = Bent(arm);
  double before = d->Evaluate(q, false).dexterity, first = before;
  for (int k = 0; k < 30; ++k) {
    const SolveStats s = solver.Solve(&q);
    EXPECT_LE(s.max_violation, 1e-10);
    const double now = d->Evaluate(q, false).dexterity;
    EXPECT_GE(now, before - 1e-12) << k;
    before = now;
  }
  std::printf("design study: dexterity %.5f -> %.5f m^3 in 30 solves\n", first, before);
  EXPECT_GT(before, first * 1.02);
}

void ExpectSameBits(const Dexterity::Measures& a, const Dexterity::Measures& b) {
  EXPECT_EQ(a.J, b.J);
  EXPECT_EQ(a.dexterity, b.dexterity);
  EXPECT_EQ(a.inverse_condition, b.inverse_condition);
  EXPECT_EQ(a.force_transmission, b.force_transmission);
  EXPECT_EQ(a.grad_dexterity, b.grad_dexterity);
  EXPECT_EQ(a.grad_inverse_condition, b.grad_inverse_condition);
  EXPECT_EQ(a.grad_force_transmission, b.grad_force_transmission);
}

TEST(DexterityTest, RecentPointsGiveTheSameBitsAsAFreshEvaluation) {
  // Each thread keeps its last points (value, then gradient at the same q: one factorization).
  // What comes from there must be what a fresh evaluation gives, whatever was evaluated before,
  // on whichever thread, and never another instance's point.
  ThreeLink arm;
  const Problem p = arm.MakeProblem();
  auto fresh = [&](const Eigen::VectorXd& q) {
    const Dexterity e(p, arm.tip, arm.joints);  // a new instance: nothing recent
    return e.Evaluate(q, true);
  };
  const Dexterity d(p, arm.tip, arm.joints);
  const Eigen::VectorXd q0 = Bent(arm);
  const Dexterity::Measures reference = fresh(q0);
  EXPECT_GT(d.Evaluate(q0, false).dexterity, 0.0);
  ExpectSameBits(d.Evaluate(q0, true), reference);  // the value's point, reused
  for (int k = 0; k < 40; ++k) {                    // more points than a thread keeps
    d.Evaluate(Bent(arm, Eigen::Vector3d(0.3 + 0.01 * k, 0.7, -0.4 - 0.005 * k)), true);
  }
  ExpectSameBits(d.Evaluate(q0, true), reference);  // evaluated again
  Dexterity::Measures on_thread;
  std::thread([&] { on_thread = d.Evaluate(q0, true); }).join();
  ExpectSameBits(on_thread, reference);
  // Another instance at the same q (another end effector) has its own measures.
  Attachment elsewhere = arm.tip;
  elsewhere.point += Eigen::Vector3d(0.0, 0.0, 0.1);
  const Dexterity other(p, elsewhere, arm.joints);
  d.Evaluate(q0, false);
  EXPECT_NE(other.Evaluate(q0, false).dexterity, reference.dexterity);
  ExpectSameBits(d.Evaluate(q0, true), reference);
}

TEST(DexterityTest, BadInputIsRejectedWithAMessage) {
  ThreeLink arm;
  const Problem p = arm.MakeProblem();
  try {
    Dexterity d(p, arm.tip, {});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "dexterity: no joint chosen");
  }
  const Dexterity two(p, arm.tip, {arm.joints[0], arm.joints[1]});
  try {
    two.Evaluate(arm.mech.InitialCoordinates(), false);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "dexterity: 2 chosen joints, but the mechanism has 3 degrees of freedom by its "
                 "equality rows");
  }
}

}  // namespace
}  // namespace tangent::optimizer
