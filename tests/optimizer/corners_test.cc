// A flat face's corner rows (optimizer/corners.h): value, gradient and Hessian against finite
// differences (≤ 1e-6 relative), over a curved rational surface and a plane, with quaternions off
// the unit sphere; unused and beyond-the-edge corners read inactive and evaluate nothing.

#include "optimizer/corners.h"

#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "nurbs/flat.h"
#include "nurbs/primitives.h"
#include "testing/alloc_counter.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kH = 1e-6;

// Relative errors of the row's gradient and of its weighted Hessian's rows against central
// differences of the value and of the analytic gradient.
std::pair<double, double> DerivativeErrors(const Mechanism& m, const Term& t, TermState* st,
                                           const Eigen::VectorXd& q) {
  Eigen::Matrix<double, 1, 14> g;
  testing::TermValue(m, t, st, q, &g);
  const double w = 0.7;
  const Eigen::Matrix<double, 14, 14> H = testing::TermHessianAt(m, t, st, q, w);
  const Eigen::Matrix<double, 14, 14> fd = testing::GradientDifferences(m, t, st, q, w, kH);
  Eigen::Matrix<double, 1, 14> g_fd;
  for (int k = 0; k < 14; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += kH;
    qm[k] -= kH;
    g_fd[k] =
        (testing::TermValue(m, t, st, qp, nullptr) - testing::TermValue(m, t, st, qm, nullptr)) /
        (2 * kH);
  }
  testing::TermValue(m, t, st, q, nullptr);
  return {(g_fd - g).cwiseAbs().maxCoeff() / g.cwiseAbs().maxCoeff(),
          (fd - H).cwiseAbs().maxCoeff() / H.cwiseAbs().maxCoeff()};
}

TEST(CornersTest, CornerRowDerivativesMatchFiniteDifferences) {
  Mechanism mech;
  const int a = mech.AddBody(Body{"box"});
  const int b = mech.AddBody(Body{"ground"});
  const nurbs::NurbsSurface face =
      nurbs::MakePlanePatch({-0.01, -0.01, 0}, {0, 0.02, 0}, {0.02, 0, 0});
  const nurbs::NurbsSurface bumpy = nurbs::MakeShearedPatch(0.3, 0.2, 0.01, true);
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.1, -0.1, 0}, {0.2, 0, 0}, {0, 0.2, 0});
  const auto quad = nurbs::FlatQuadOf(face);
  ASSERT_TRUE(quad.has_value());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_g = 0.0, worst_h = 0.0;
  int checked = 0;
  for (const nurbs::NurbsSurface* other : {&bumpy, &plane}) {
    const nurbs::SurfacePoint mid = other->Evaluate(0.5, 0.5, 1);
    const Eigen::Vector3d normal = mid.S_u.cross(mid.S_v).normalized();
    for (int trial = 0; trial < 6; ++trial) {
      // The box near the other surface's middle, its face `gap` over it and tilted; quaternions
      // scaled off the unit sphere.
      const Eigen::Quaterniond qa(1, 0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng));
      const Eigen::Quaterniond qb(1, 0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng));
      const Eigen::Vector3d pb(0.002 * u(rng), 0.002 * u(rng), 0.002 * u(rng));
      const Eigen::Vector3d pa = pb + qb.normalized() * (mid.S + (0.004 + 0.003 * u(rng)) * normal);
      Eigen::VectorXd q(14);
      q << pa, 1.2 * qa.w(), 1.2 * qa.x(), 1.2 * qa.y(), 1.2 * qa.z(), pb, 0.9 * qb.w(),
          0.9 * qb.x(), 0.9 * qb.y(), 0.9 * qb.z();
      for (int c = 0; c < 4; ++c) {
        const auto term =
            MakeCornerContact({a, quad->points[static_cast<size_t>(c)]}, b, other, {0.5, 0.5});
        const std::unique_ptr<TermState> st = term->MakeState();
        auto& s = static_cast<CornerContactTerm::State&>(*st);
        s.Activate({0.5, 0.5});
        testing::TermValue(mech, *term, st.get(), q, nullptr);
        ASSERT_TRUE(s.over());
        const auto [eg, eh] = DerivativeErrors(mech, *term, st.get(), q);
        worst_g = std::max(worst_g, eg);
        worst_h = std::max(worst_h, eh);
        ++checked;
      }
    }
  }
  std::printf("corner rows: %d checked, gradient %.1e, Hessian %.1e relative\n", checked, worst_g,
              worst_h);
  EXPECT_LT(worst_g, 1e-6);
  EXPECT_LT(worst_h, 1e-6);
}

TEST(CornersTest, UnusedAndBeyondTheEdgeCornersReadInactiveWithoutAllocating) {
  Mechanism mech;
  const int a = mech.AddBody(Body{"box"});
  const int b = mech.AddBody(Body{"ground"});
  const nurbs::NurbsSurface plane =
      nurbs::MakePlanePatch({-0.1, -0.1, 0}, {0.2, 0, 0}, {0, 0.2, 0});
  const auto term = MakeCornerContact({a, Eigen::Vector3d(0.01, 0.01, 0)}, b, &plane, {0.5, 0.5});
  const std::unique_ptr<TermState> st = term->MakeState();
  auto& s = static_cast<CornerContactTerm::State&>(*st);
  Eigen::VectorXd q(14);
  q << 0, 0, 0.003, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0;
  Eigen::Matrix<double, 1, 14> g;
  EXPECT_TRUE(term->Idle(st.get()));
  EXPECT_EQ(testing::TermValue(mech, *term, st.get(), q, &g), ContactSlotState::kInactiveDistance);
  EXPECT_EQ(g.cwiseAbs().maxCoeff(), 0.0);
  s.Activate({0.5, 0.5});
  EXPECT_NEAR(testing::TermValue(mech, *term, st.get(), q, &g), 0.003, 1e-16);
  EXPECT_NEAR(g[2], 1.0, 1e-15);  // ∂β/∂z of the box
  // Moved beyond the plane's edge: the corner lies over nothing and holds nothing.
  q[0] = 0.2;
  EXPECT_EQ(testing::TermValue(mech, *term, st.get(), q, &g), ContactSlotState::kInactiveDistance);
  EXPECT_FALSE(s.over());
  // Evaluating allocates nothing (Hessian included).
  std::vector<contact::BodyPose> poses;
  q[0] = 0.0;
  mech.Poses(q, &poses);
  Eigen::VectorXd r(1);
  Eigen::MatrixXd Ja(1, 7), Jb(1, 7);
  TermHessian h;
  h.SetZero();
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(1, 0.5);
  const long before = testing::AllocationCount();
  for (int k = 0; k < 10; ++k) {
    poses[0].q[2] = 0.003 + 1e-5 * k;
    term->Evaluate(poses, st.get(), r, Ja, Jb);
    term->AddWeightedHessian(poses, st.get(), w, &h);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_NEAR(r[0], 0.003 + 9e-5, 1e-16);
}

}  // namespace
}  // namespace tangent::optimizer
