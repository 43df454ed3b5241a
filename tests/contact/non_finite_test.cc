// Every public entry point of the kernel and the contact solvers is total on non-finite and
// absurd input (issue 13): a clear error at the boundary (constructors), or a defined state on
// the servo path (clamped parameters, ExtremalStatus::kInvalidInput), never NaN out and never
// an index outside the net (FindSpan(NaN) used to return one, and the reference and refinement
// paths then read past the control net: AddressSanitizer, heap-buffer-overflow).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "contact/contact_jacobian.h"
#include "contact/extremal.h"
#include "nurbs/curve.h"
#include "nurbs/primitives.h"
#include "nurbs/refinement.h"
#include "nurbs/surface.h"

namespace tangent::contact {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

bool Finite(const nurbs::SurfacePoint& p) {
  return p.S.allFinite() && p.S_u.allFinite() && p.S_v.allFinite() && p.S_uu.allFinite() &&
         p.S_uv.allFinite() && p.S_vv.allFinite();
}

nurbs::NurbsSurface Patch() { return nurbs::MakeShearedPatch(0.3, 0.2, 0.01, /*rational=*/true); }

TEST(NonFiniteTest, FindSpanStaysInsideTheKnotVector) {
  const nurbs::NurbsSurface s = Patch();
  for (const nurbs::KnotVector* k : {&s.knots_u(), &s.knots_v()}) {
    for (double t : {kNaN, kInf, -kInf, 1e308, -1e308}) {
      for (int hint : {-5, 0, 3, 1000}) {
        const int span = k->FindSpan(t, hint);
        EXPECT_GE(span, k->degree()) << t;
        EXPECT_LT(span, k->num_basis()) << t;
      }
    }
    EXPECT_EQ(k->Clamp(kNaN), k->domain_begin());
    EXPECT_EQ(k->Clamp(kInf), k->domain_end());
    EXPECT_EQ(k->Clamp(-kInf), k->domain_begin());
  }
}

TEST(NonFiniteTest, EveryEvaluationPathGivesTheClampedPointNeverNaN) {
  const nurbs::NurbsSurface s = Patch();
  const double u0 = s.knots_u().domain_begin(), u1 = s.knots_u().domain_end();
  const double v0 = s.knots_v().domain_begin();
  const double cases[][3] = {{kNaN, 0.5, u0}, {kInf, 0.5, u1}, {-kInf, 0.5, u0}};
  for (const auto& c : cases) {
    const nurbs::SurfacePoint expected = s.Evaluate(c[2], 0.5);
    const nurbs::SurfacePoint paths[3] = {s.Evaluate(c[0], c[1]),
                                          nurbs::EvaluateReference(s, c[0], c[1]),
                                          nurbs::EvaluateByRefinement(s, c[0], c[1])};
    for (const nurbs::SurfacePoint& p : paths) {
      ASSERT_TRUE(Finite(p)) << c[0];
      EXPECT_LT((p.S - expected.S).norm(), 1e-14) << c[0];
    }
  }
  EXPECT_TRUE(Finite(s.Evaluate(kNaN, kNaN)));
  EXPECT_LT((s.Evaluate(kNaN, kNaN).S - s.Evaluate(u0, v0).S).norm(), 1e-14);
  // A rational quadratic quarter circle.
  const nurbs::NurbsCurve<3> c(
      nurbs::KnotVector(2, {0, 0, 0, 1, 1, 1}),
      {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 1, 0)},
      {1.0, std::sqrt(0.5), 1.0});
  for (double t : {kNaN, kInf, -kInf}) {
    const nurbs::CurvePoint<3> paths[3] = {c.Evaluate(t), nurbs::EvaluateReference(c, t),
                                           nurbs::EvaluateByRefinement(c, t)};
    for (const auto& p : paths) {
      EXPECT_TRUE(p.C.allFinite() && p.C1.allFinite() && p.C2.allFinite()) << t;
    }
  }
}

std::string ConstructionError(double weight, double coordinate) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      pts.emplace_back(i, j, i == 1 && j == 1 ? coordinate : 0.0);
      w.push_back(i == 1 && j == 0 ? weight : 1.0);
    }
  }
  try {
    nurbs::NurbsSurface s(nurbs::KnotVector(1, {0, 0, 1, 1}), nurbs::KnotVector(1, {0, 0, 1, 1}),
                          pts, w);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(NonFiniteTest, WeightsAndCoordinatesWhoseProductsOverflowAreRejected) {
  EXPECT_EQ(ConstructionError(1.0, 1.0), "(accepted)");
  EXPECT_EQ(ConstructionError(1e99, 1.0), "(accepted)");
  EXPECT_NE(ConstructionError(1e300, 1.0)
                .find("NURBS surface: control point [1][0] (1 0 0) with "
                      "weight 1e+300 is out of range"),
            std::string::npos)
      << ConstructionError(1e300, 1.0);
  EXPECT_NE(ConstructionError(1e-300, 1.0).find("weights must lie in [1e-100, 1e100]"),
            std::string::npos);
  EXPECT_NE(ConstructionError(1.0, 1e200).find("control point [1][1]"), std::string::npos);
  EXPECT_NE(ConstructionError(kNaN, 1.0).find("must be positive and finite"), std::string::npos);
  // The homogeneous constructor holds the same bounds.
  std::vector<Eigen::Vector4d> cpw(4, Eigen::Vector4d(0, 0, 0, 1));
  cpw[3] << 1e250, 0, 0, 1e200;  // P = 1e50 but w = 1e200: w·P overflows the bound
  EXPECT_THROW(nurbs::NurbsSurface::FromHomogeneous(nurbs::KnotVector(1, {0, 0, 1, 1}),
                                                    nurbs::KnotVector(1, {0, 0, 1, 1}), cpw),
               std::invalid_argument);
}

TEST(NonFiniteTest, ExtremalSolversReturnADefinedInvalidInputState) {
  const nurbs::NurbsSurface f = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface g = Patch();
  Vector7d q;
  q << 0, 0, 0.2, 1, 0, 0, 0;
  const BodyPose good = BodyPose::FromCoordinates(q);
  const BodyPose ground = BodyPose::FromCoordinates((Vector7d() << 0, 0, 0, 1, 0, 0, 0).finished());
  Vector7d zero_q = q;
  zero_q.tail<4>().setZero();  // a zero quaternion: no rotation at all
  const BodyPose zero = BodyPose::FromCoordinates(zero_q);
  Vector7d nan_q = q;
  nan_q[1] = kNaN;
  const BodyPose nan_pose = BodyPose::FromCoordinates(nan_q);
  auto check = [](const SurfaceSurfaceExtremum& e, const char* what) {
    EXPECT_EQ(e.status, ExtremalStatus::kInvalidInput) << what;
    EXPECT_TRUE(e.u.allFinite()) << what;
    EXPECT_FALSE(std::isnan(e.beta)) << what;
    EXPECT_TRUE(e.p_f.allFinite() && e.p_g.allFinite() && e.n_g.allFinite()) << what;
    EXPECT_TRUE(e.R_WCf.allFinite() && e.R_WCg.allFinite()) << what;
    EXPECT_STREQ(ToString(e.status), "invalid_input");
  };
  check(SolveSurfaceSurface(f, good, g, ground, Eigen::Vector4d(kNaN, 0.5, 0.5, 0.5)), "NaN seed");
  check(SolveSurfaceSurface(f, good, g, ground, Eigen::Vector4d(0.5, kInf, 0.5, 0.5)), "inf seed");
  check(SolveSurfaceSurface(f, zero, g, ground, Eigen::Vector4d::Constant(0.5)), "zero quaternion");
  check(SolveSurfaceSurface(f, nan_pose, g, ground, Eigen::Vector4d::Constant(0.5)), "NaN pose");
  // A finite seed and poses still solve.
  EXPECT_NE(SolveSurfaceSurface(f, good, g, ground, Eigen::Vector4d::Constant(0.5)).status,
            ExtremalStatus::kInvalidInput);
  const PointSurfaceExtremum p =
      SolvePointSurface(Eigen::Vector3d(kNaN, 0, 0), g, ground, Eigen::Vector2d(0.5, 0.5));
  EXPECT_EQ(p.status, ExtremalStatus::kInvalidInput);
  EXPECT_FALSE(std::isnan(p.distance));
  EXPECT_TRUE(p.u.allFinite() && p.p_f.allFinite() && p.R_WCf.allFinite());
  const PointSurfaceExtremum p2 =
      SolvePointSurface(Eigen::Vector3d(0, 0, 1), g, ground, Eigen::Vector2d(kNaN, 0.5));
  EXPECT_EQ(p2.status, ExtremalStatus::kInvalidInput);
  EXPECT_TRUE(p2.u.allFinite());
}

// Montana's formula holds for facing normals only: a pair whose normals point the same way (a
// ball inside a larger one, σ = +1) is refused, where it used to return true with 150 % error.
TEST(NonFiniteTest, MontanasPreconditionIsChecked) {
  const nurbs::NurbsSurface inner = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05);
  const nurbs::NurbsSurface outer = nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.2);
  Vector7d qi, qo;
  qi << 0.03, 0.01, 0.0, 1, 0, 0, 0;
  qo << 0, 0, 0, 1, 0, 0, 0;
  const BodyPose pi = BodyPose::FromCoordinates(qi), po = BodyPose::FromCoordinates(qo);
  const Eigen::Vector4d seed = ClosestSamplePair(inner, pi, outer, po, 20);
  SurfacePairEval e;
  const SurfaceSurfaceExtremum x = SolveSurfaceSurface(inner, pi, outer, po, seed, {}, &e);
  ASSERT_EQ(x.status, ExtremalStatus::kConverged);
  ASSERT_GT(x.alignment, 0.99);  // same-direction normals
  Matrix4x14 u_q;
  EXPECT_FALSE(ContactJacobianMontana(e, pi, po, &u_q));
}

}  // namespace
}  // namespace tangent::contact
