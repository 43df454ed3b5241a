// Every joint, limit and goal: analytic Jacobian blocks against central finite differences of
// the term over both bodies' 7 coordinates, at seeded random poses (including quaternions off
// the unit sphere, which the normalized placement must ignore except in UnitQuaternion).

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "optimizer/goals.h"
#include "optimizer/joints.h"

namespace tangent::optimizer {
namespace {

// h = 1e-6 on O(1) coordinates: truncation ~1e-12, rounding ~1e-10 (terms are O(1));
// 1e-7 absolute leaves three digits.
constexpr double kH = 1e-6;
constexpr double kTol = 1e-7;

struct Fixture {
  Mechanism mech;
  int a, b, ground;
  Fixture() {
    Body ba{"a"}, bb{"b"}, g{"ground"};
    g.fixed = true;
    ground = mech.AddBody(g);
    a = mech.AddBody(ba);
    b = mech.AddBody(bb);
  }
};

Eigen::VectorXd RandomCoordinates(std::mt19937_64& rng, int n) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = g(rng);
  for (int o = 0; o < n; o += 7) q.segment<4>(o + 3) *= 1.2 / q.segment<4>(o + 3).norm();
  return q;
}

// Calls fn(side, k, q + h e, q − h e) for each of the 7 coordinates of each moving body of term.
template <class Fn>
void ForEachCoordinate(const Fixture& f, const Term& term, const Eigen::VectorXd& q, Fn&& fn) {
  for (int side = 0; side < 2; ++side) {
    const int body = side == 0 ? term.body_a() : term.body_b();
    if (body < 0 || f.mech.offset(body) < 0) continue;
    for (int k = 0; k < 7; ++k) {
      Eigen::VectorXd qp = q, qm = q;
      qp[f.mech.offset(body) + k] += kH;
      qm[f.mech.offset(body) + k] -= kH;
      fn(side, k, qp, qm);
    }
  }
}

// Evaluations with the term's own fresh per-solve state (goal targets as constructed).
void Eval(const Term& t, const std::vector<BodyPose>& poses, Eigen::VectorXd& r,
          Eigen::MatrixXd& J_a, Eigen::MatrixXd& J_b) {
  const std::unique_ptr<TermState> st = t.MakeState();
  t.Evaluate(poses, st.get(), r, J_a, J_b);
}
void AddHessian(const Term& t, const std::vector<BodyPose>& poses, const Eigen::VectorXd& w,
                TermHessian* h) {
  const std::unique_ptr<TermState> st = t.MakeState();
  t.AddWeightedHessian(poses, st.get(), w, h);
}

void CheckTermAt(const Fixture& f, const Term& term, const Eigen::VectorXd& q) {
  {
    std::vector<BodyPose> poses;
    f.mech.Poses(q, &poses);
    const int m = term.dim();
    Eigen::VectorXd r(m);
    Eigen::MatrixXd Ja(m, 7), Jb(m, 7);
    Eval(term, poses, r, Ja, Jb);
    ASSERT_TRUE(r.allFinite()) << term.name();
    ForEachCoordinate(f, term, q,
                      [&](int side, int k, const Eigen::VectorXd& qp, const Eigen::VectorXd& qm) {
                        std::vector<BodyPose> pp, pm;
                        f.mech.Poses(qp, &pp);
                        f.mech.Poses(qm, &pm);
                        Eigen::VectorXd rp(m), rm(m);
                        Eigen::MatrixXd s1(m, 7), s2(m, 7);
                        Eval(term, pp, rp, s1, s2);
                        Eval(term, pm, rm, s1, s2);
                        const Eigen::VectorXd fd = (rp - rm) / (2 * kH);
                        const Eigen::VectorXd an = side == 0 ? Ja.col(k) : Jb.col(k);
                        EXPECT_LT((fd - an).cwiseAbs().maxCoeff(), kTol)
                            << term.name() << " body " << side << " coordinate " << k;
                      });
  }
}

// Σ w_i ∇²r_i against finite differences of the weighted gradient Jᵀw over both bodies.
void CheckTerm(const Fixture& f, const Term& term, std::mt19937_64& rng) {
  for (int trial = 0; trial < 5; ++trial) {
    CheckTermAt(f, term, RandomCoordinates(rng, f.mech.num_coordinates()));
  }
}

void CheckHessianAt(const Fixture& f, const Term& term, const Eigen::VectorXd& q,
                    std::mt19937_64& rng) {
  if (!term.has_hessian()) return;
  std::normal_distribution<double> g(0.0, 1.0);
  const int m = term.dim();
  {
    Eigen::VectorXd w(m);
    for (int i = 0; i < m; ++i) w[i] = g(rng);
    std::vector<BodyPose> poses;
    f.mech.Poses(q, &poses);
    TermHessian h;
    h.SetZero();
    AddHessian(term, poses, w, &h);
    const int b = term.body_b() >= 0 ? term.body_b() : term.body_a();
    h.Fold(poses[static_cast<size_t>(term.body_a())].q.tail<4>(),
           poses[static_cast<size_t>(b)].q.tail<4>());
    const Matrix7d &Haa = h.aa, &Hab = h.ab, &Hbb = h.bb;
    auto weighted_gradient = [&](const Eigen::VectorXd& x, Eigen::Matrix<double, 7, 1>* ga,
                                 Eigen::Matrix<double, 7, 1>* gb) {
      std::vector<BodyPose> p;
      f.mech.Poses(x, &p);
      Eigen::VectorXd r(m);
      Eigen::MatrixXd Ja(m, 7), Jb(m, 7);
      Eval(term, p, r, Ja, Jb);
      *ga = Ja.transpose() * w;
      *gb = Jb.transpose() * w;
    };
    ForEachCoordinate(
        f, term, q, [&](int side, int k, const Eigen::VectorXd& qp, const Eigen::VectorXd& qm) {
          Eigen::Matrix<double, 7, 1> gap, gbp, gam, gbm;
          weighted_gradient(qp, &gap, &gbp);
          weighted_gradient(qm, &gam, &gbm);
          const Eigen::Matrix<double, 7, 1> dga = (gap - gam) / (2 * kH),
                                            dgb = (gbp - gbm) / (2 * kH);
          // Column k of ∂g_a/∂q_side and ∂g_b/∂q_side.
          const Eigen::Matrix<double, 7, 1> an_a = side == 0
                                                       ? Eigen::Matrix<double, 7, 1>(Haa.col(k))
                                                       : Eigen::Matrix<double, 7, 1>(Hab.col(k));
          const Eigen::Matrix<double, 7, 1> an_b =
              side == 0 ? Eigen::Matrix<double, 7, 1>(Hab.row(k).transpose())
                        : Eigen::Matrix<double, 7, 1>(Hbb.col(k));
          EXPECT_LT((dga - an_a).cwiseAbs().maxCoeff(), 1e-6)
              << term.name() << " H_a* side " << side << " k " << k;
          if (term.body_b() >= 0 && f.mech.offset(term.body_b()) >= 0) {
            EXPECT_LT((dgb - an_b).cwiseAbs().maxCoeff(), 1e-6)
                << term.name() << " H_b* side " << side << " k " << k;
          }
        });
  }
}

void CheckHessian(const Fixture& f, const Term& term, std::mt19937_64& rng) {
  for (int trial = 0; trial < 3; ++trial) {
    CheckHessianAt(f, term, RandomCoordinates(rng, f.mech.num_coordinates()), rng);
  }
}

TEST(TermsTest, JointJacobiansMatchFiniteDifferences) {
  Fixture f;
  std::mt19937_64 rng(31);
  const Attachment a{f.a, {0.1, -0.2, 0.3}, {0.3, 0.5, -1.0}, {1, 0, 0.2}};
  const Attachment b{f.b, {-0.3, 0.1, 0.05}, {0.0, 1.0, 0.4}, {0.2, 0.1, 1}};
  const Attachment g{f.ground, {0.5, 0.5, 0}, {0, 0, 1}, {1, 0, 0}};
  for (const TermPtr& t :
       {SphericalJoint(a, b), RevoluteJoint(a, b), UniversalJoint(a, b), CylindricalJoint(a, b),
        PrismaticJoint(a, b), FixedJoint(a, b), RevoluteJoint(g, b), UnitQuaternion(f.a),
        RevoluteLimits(a, b, -1.0, 2.0), PrismaticLimits(a, b, -0.5, 0.25),
        JointCoordinate("prismatic", a, b), JointCoordinate("revolute", a, b)}) {
    CheckTerm(f, *t, rng);
    CheckHessian(f, *t, rng);
  }
}

TEST(TermsTest, GoalJacobiansMatchFiniteDifferences) {
  Fixture f;
  std::mt19937_64 rng(32);
  const Attachment a{f.a, {0.1, -0.2, 0.3}, {0.3, 0.5, -1.0}, {1, 0, 0}};
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.5, -0.4, 2.0);
  for (const TermPtr& g :
       {PositionGoal(a, t), OrientationGoal(f.a, R, {1.0, 0.5, 0.0}), PoseGoal(a, t, R, {1, 1, 1}),
        AimingGoal(a, {4, 5, 6}), LineGoal(a, t, {1, 1, 0}), PlaneGoal(a, t, {0, 0.3, 1}),
        HalfSpaceGoal(a, t, {0, 0.3, 1}, false),
        DisjunctionGoal({PositionGoal(a, t), PositionGoal(a, -t)})}) {
    CheckTerm(f, *g, rng);
    CheckHessian(f, *g, rng);
  }
}

TEST(TermsTest, JointsVanishWhenAssembled) {
  // Two bodies placed so the attachments agree: every joint row is zero.
  Fixture f;
  const Eigen::Quaterniond qa(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 0, 1).normalized()));
  const Eigen::Vector3d pa(0.2, 0.3, -0.1);
  const Eigen::Vector3d point_a(0.1, 0.0, 0.2), axis_a(0, 0, 1), ref_a(1, 0, 0);
  // b's frame is a's frame shifted so that b's attachment (origin, same axes) sits on a's.
  Eigen::VectorXd q(14);
  q << pa, qa.w(), qa.x(), qa.y(), qa.z(), pa + qa * point_a, qa.w(), qa.x(), qa.y(), qa.z();
  std::vector<BodyPose> poses;
  f.mech.Poses(q, &poses);
  const Attachment a{f.a, point_a, axis_a, ref_a};
  const Attachment b{f.b, Eigen::Vector3d::Zero(), axis_a, ref_a};
  for (const TermPtr& t : {SphericalJoint(a, b), RevoluteJoint(a, b), CylindricalJoint(a, b),
                           PrismaticJoint(a, b), FixedJoint(a, b)}) {
    Eigen::VectorXd r(t->dim());
    Eigen::MatrixXd J1(t->dim(), 7), J2(t->dim(), 7);
    Eval(*t, poses, r, J1, J2);
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-15) << t->name();
  }
}

// Issue 13: "axes parallel" must not accept antiparallel axes, and a weld must not accept a half
// turn. Body b is placed on a's attachment (the joint assembled), then turned by a half turn
// about a's reference (axis reversed), about the axis (reference reversed) or about their
// cross product: every one of those is now far from zero, the assembled pose still exactly zero,
// and the mapped rows' derivatives (far hemisphere) match finite differences.
TEST(TermsTest, FlippedMountingsAreNotSolutions) {
  Fixture f;
  const Eigen::Quaterniond qa(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 0, 1).normalized()));
  const Eigen::Vector3d pa(0.2, 0.3, -0.1), point_a(0.1, 0.0, 0.2), axis(0, 0, 1), ref(1, 0, 0);
  const Attachment a{f.a, point_a, axis, ref};
  const Attachment b{f.b, Eigen::Vector3d::Zero(), axis, ref};
  auto pose = [&](const Eigen::Quaterniond& turn) {  // b's frame = a's frame turned, at a's point
    const Eigen::Quaterniond qb = qa * turn;
    Eigen::VectorXd q(14);
    q << pa, qa.w(), qa.x(), qa.y(), qa.z(), pa + qa * point_a, qb.w(), qb.x(), qb.y(), qb.z();
    return q;
  };
  auto residual = [&](const Term& t, const Eigen::VectorXd& q) {
    std::vector<BodyPose> poses;
    f.mech.Poses(q, &poses);
    Eigen::VectorXd r(t.dim());
    Eigen::MatrixXd J1(t.dim(), 7), J2(t.dim(), 7);
    Eval(t, poses, r, J1, J2);
    return r.norm();
  };
  const double pi = std::numbers::pi;
  const Eigen::Quaterniond flips[3] = {
      Eigen::Quaterniond(Eigen::AngleAxisd(pi, ref)),               // axis reversed
      Eigen::Quaterniond(Eigen::AngleAxisd(pi, axis)),              // half turn about the axis
      Eigen::Quaterniond(Eigen::AngleAxisd(pi, axis.cross(ref)))};  // both reversed
  std::mt19937_64 rng(33);
  for (const TermPtr& t :
       {RevoluteJoint(a, b), CylindricalJoint(a, b), PrismaticJoint(a, b), FixedJoint(a, b)}) {
    EXPECT_LT(residual(*t, pose(Eigen::Quaterniond::Identity())), 1e-15) << t->name();
    const bool turns_matter = t->name() == "prismatic" || t->name() == "fixed";
    for (int k = 0; k < 3; ++k) {
      const double r = residual(*t, pose(flips[k]));
      if (k == 1 && !turns_matter) {
        EXPECT_LT(r, 1e-15) << t->name() << ": a turn about the axis is this joint's motion";
      } else {
        EXPECT_GE(r, 1.9) << t->name() << " flip " << k;
      }
      // Just short of the flip (far hemisphere): derivatives against finite differences.
      const Eigen::Quaterniond near_flip =
          flips[k] *
          Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
      CheckTermAt(f, *t, pose(near_flip));
      CheckHessianAt(f, *t, pose(near_flip), rng);
    }
  }
}

TEST(TermsTest, BadInputIsRejectedWithAMessage) {
  Mechanism m;
  Body bad{"wrist"};
  bad.mass = -1;
  try {
    m.AddBody(bad);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "body \"wrist\": mass must be positive and finite");
  }
  const Attachment a{0, {0, 0, 0}, {0, 0, 1}, {0, 0, 2}};
  EXPECT_THROW(RevoluteJoint(a, a), std::invalid_argument);  // Reference parallel to axis.
  EXPECT_THROW(LineGoal(a, {0, 0, 0}, {0, 0, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace tangent::optimizer
