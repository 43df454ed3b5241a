// Edge against edge (issue 34): the extremal distance between two trim edges of two curved
// faces on two bodies, each edge a curve in its face's parameter domain mapped through the face.
// Against a dense-sampling truth; the parameters' motion with the poses against central
// differences of re-solves; the distance's gradient and Hessian against differences of re-solved
// distances and of the analytic gradient.

#include "contact/edge_edge.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "nurbs/primitives.h"

namespace tangent::contact {
namespace {

// As jacobian_test: h = 1e-6 on coordinates of size O(0.1 m) and O(1); truncation ~1e-10 and
// rounding ~1e-9 relative, three digits under the 1e-6.
constexpr double kH = 1e-6;
constexpr double kRelTol = 1e-6;

double RelError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& ref) {
  return (a - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff();
}

Vector7d Coordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

// A: a rational sheared patch with a circular hole (its rim a periodic trim circle). B: a
// cylinder's face cut by a straight line of its domain at v = 0.3 (a circle round the
// cylinder's axis in space), lying across the hole's rim above it, turned and tilted.
struct Scene {
  nurbs::NurbsSurface patch =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, 0.01, true);
  nurbs::NurbsCurve2d hole = nurbs::MakeCircle2d({0.5, 0.5}, 0.2);
  nurbs::NurbsSurface cylinder = nurbs::MakeCylinder(0.015, 0.05);
  nurbs::NurbsCurve2d cut = nurbs::MakePolyline2d({{0.0, 0.3}, {1.0, 0.3}});
  BodyCurve rim{&patch, &hole, /*periodic=*/true};
  BodyCurve edge{&cylinder, &cut};
  Vector7d q_a = Coordinates({0.0, 0.0, 0.0}, Eigen::Quaterniond::Identity());
  Vector7d QB(double lift) const {
    const Eigen::Vector3d centre =
        patch.Evaluate(0.5 + 0.2 * std::cos(0.4), 0.5 + 0.2 * std::sin(0.4), 0).S;
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(std::numbers::pi / 2 - 0.2, Eigen::Vector3d::UnitY()));
    return Coordinates(centre + Eigen::Vector3d(-0.004, 0.002, 0.015 + lift), q);
  }
};

// The closest pair of 4000 samples on each edge, then 200 × 200 on a window of ±2 coarse steps
// around it: an upper bound of the minimum within ~1e-8 m of it.
Eigen::Vector2d SampledClosest(const Scene& s, const BodyPose& pa, const BodyPose& pb,
                               double* distance) {
  auto point = [](const BodyCurve& c, const BodyPose& p, double t) {
    int span = 0;
    nurbs::SpanHint hint;
    return p.Point(c.Evaluate(t, &span, &hint).C);
  };
  auto best_in = [&](double s0, double s1, double t0, double t1, int n) {
    std::vector<Eigen::Vector3d> b(static_cast<size_t>(n + 1));
    for (int j = 0; j <= n; ++j)
      b[static_cast<size_t>(j)] = point(s.edge, pb, t0 + (t1 - t0) * j / n);
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d x;
    for (int i = 0; i <= n; ++i) {
      const double si = s0 + (s1 - s0) * i / n;
      const Eigen::Vector3d a = point(s.rim, pa, si);
      for (int j = 0; j <= n; ++j) {
        const double d = (a - b[static_cast<size_t>(j)]).squaredNorm();
        if (d < best) {
          best = d;
          x = {si, t0 + (t1 - t0) * j / n};
        }
      }
    }
    *distance = std::sqrt(best);
    return x;
  };
  const Eigen::Vector2d coarse = best_in(0.0, 1.0, 0.0, 1.0, 4000);
  constexpr double w = 2.0 / 4000;
  return best_in(coarse[0] - w, coarse[0] + w, std::max(0.0, coarse[1] - w),
                 std::min(1.0, coarse[1] + w), 200);
}

// Re-solves the edges' extremum from `x` at the poses with coordinate i (A's 0–6, then B's)
// moved by +h (k = 0) and by −h (k = 1), handing each to use(k, extremum, evaluation, poses).
template <typename Use>
void ResolvedAround(const Scene& s, const Vector7d& qa, const Vector7d& qb, int i, double h,
                    const Eigen::Vector2d& x, Use&& use) {
  for (int k = 0; k < 2; ++k) {
    Vector7d a = qa, b = qb;
    (i < 7 ? a[i] : b[i - 7]) += (k == 0 ? h : -h);
    const BodyPose pa = BodyPose::FromCoordinates(a), pb = BodyPose::FromCoordinates(b);
    CurveCurveEval at;
    const CurveCurveExtremum e = SolveCurveCurve(s.rim, pa, s.edge, pb, x, {}, &at);
    use(k, e, at, pa, pb);
  }
}

TEST(EdgeEdgeTest, TheMinimumOfTwoTrimEdgesOfCurvedFaces) {
  const Scene s;
  for (const double lift : {0.0, -0.004, 0.01}) {
    const BodyPose pa = BodyPose::FromCoordinates(s.q_a);
    const BodyPose pb = BodyPose::FromCoordinates(s.QB(lift));
    double sampled = 0.0;
    const Eigen::Vector2d near = SampledClosest(s, pa, pb, &sampled);
    const Eigen::Vector2d beside =
        (near + Eigen::Vector2d(0.03, -0.03)).cwiseMax(0.0).cwiseMin(1.0).eval();
    for (const Eigen::Vector2d& seed : {near, beside}) {
      const CurveCurveExtremum e = SolveCurveCurve(s.rim, pa, s.edge, pb, seed);
      ASSERT_EQ(e.status, ExtremalStatus::kConverged) << "lift " << lift;
      EXPECT_EQ(e.kind, ExtremumKind::kMinimum);
      EXPECT_LE(e.distance, sampled + 1e-12) << "lift " << lift;
      EXPECT_GT(e.distance, sampled - 1e-7) << "lift " << lift;
      EXPECT_LE(e.iterations, 8);
      // At the minimum d is perpendicular to both edges.
      CurveCurveEval at;
      int sa = 0, sb = 0;
      nurbs::SpanHint ha, hb;
      EvaluateCurveCurve(s.rim, pa, s.edge, pb, e.x, &sa, &ha, &sb, &hb, &at);
      EXPECT_LT(std::abs(at.grad[0]) / (at.a.world.C1.norm() * std::max(e.distance, 1e-9)), 1e-10);
      EXPECT_LT(std::abs(at.grad[1]) / (at.b.world.C1.norm() * std::max(e.distance, 1e-9)), 1e-10);
    }
    std::printf("lift %+.3f m: edge–edge distance %.9f m (sampled %.9f)\n", lift,
                SolveCurveCurve(s.rim, pa, s.edge, pb, near).distance, sampled);
  }
}

TEST(EdgeEdgeTest, TouchingEdgesConvergeWithARegularSystem) {
  const Scene s;
  const BodyPose pa = BodyPose::FromCoordinates(s.q_a);
  // Lower B until the edges touch: its distance at lift 0, taken off along the contact's d.
  BodyPose pb = BodyPose::FromCoordinates(s.QB(0.0));
  double sampled = 0.0;
  const CurveCurveExtremum apart =
      SolveCurveCurve(s.rim, pa, s.edge, pb, SampledClosest(s, pa, pb, &sampled));
  Vector7d q = s.QB(0.0);
  q.head<3>() += (apart.p_a - apart.p_b);  // B's point moved onto A's
  pb = BodyPose::FromCoordinates(q);
  CurveCurveEval at;
  const CurveCurveExtremum e = SolveCurveCurve(s.rim, pa, s.edge, pb, apart.x, {}, &at);
  EXPECT_EQ(e.status, ExtremalStatus::kConverged);
  EXPECT_LT(e.distance, 1e-15);
  EXPECT_LT((e.x - apart.x).norm(), 1e-12);
  // The system's determinant there is |a' × b'|²: regular for edges that cross.
  const double cross = at.a.world.C1.cross(at.b.world.C1).squaredNorm();
  EXPECT_NEAR(at.hess.determinant(), cross, 1e-9 * cross);
  Matrix2x14 x_q;
  EXPECT_TRUE(CurveCurveJacobian(at, pa, pb, &x_q));
}

TEST(EdgeEdgeTest, JacobianGradientAndHessianMatchFiniteDifferences) {
  const Scene s;
  for (const double lift : {0.0, 0.01}) {
    const Vector7d qa = s.q_a, qb = s.QB(lift);
    const BodyPose pa = BodyPose::FromCoordinates(qa), pb = BodyPose::FromCoordinates(qb);
    double sampled = 0.0;
    CurveCurveEval at;
    const CurveCurveExtremum e =
        SolveCurveCurve(s.rim, pa, s.edge, pb, SampledClosest(s, pa, pb, &sampled), {}, &at);
    ASSERT_EQ(e.status, ExtremalStatus::kConverged);
    Matrix2x14 x_q;
    ASSERT_TRUE(CurveCurveJacobian(at, pa, pb, &x_q));
    const Row14 grad = CurveCurveDistanceGradient(at, pa, pb);
    const Matrix14d hess = CurveCurveDistanceHessian(at, pa, pb, x_q);
    Matrix2x14 fd_x;
    Row14 fd_grad;
    Matrix14d fd_hess;
    for (int i = 0; i < 14; ++i) {
      Eigen::Vector2d x[2];
      double dist[2];
      Row14 g[2];
      ResolvedAround(s, qa, qb, i, kH, e.x,
                     [&](int k, const CurveCurveExtremum& r, const CurveCurveEval& ek,
                         const BodyPose& pa_k, const BodyPose& pb_k) {
                       x[k] = r.x;
                       dist[k] = r.distance;
                       g[k] = CurveCurveDistanceGradient(ek, pa_k, pb_k);
                     });
      fd_x.col(i) = (x[0] - x[1]) / (2 * kH);
      fd_grad[i] = (dist[0] - dist[1]) / (2 * kH);
      fd_hess.col(i) = (g[0] - g[1]).transpose() / (2 * kH);
    }
    EXPECT_LT(RelError(x_q, fd_x), kRelTol) << "lift " << lift;
    EXPECT_LT(RelError(grad, fd_grad), kRelTol) << "lift " << lift;
    EXPECT_LT(RelError(hess, fd_hess), kRelTol) << "lift " << lift;
    EXPECT_LT(RelError(hess, hess.transpose()), 1e-9) << "lift " << lift;
    std::printf("lift %+.3f m: x_q %.1e, gradient %.1e, Hessian %.1e relative to differences\n",
                lift, RelError(x_q, fd_x), RelError(grad, fd_grad), RelError(hess, fd_hess));
  }
}

// The signed row β = d·ν along the edges' common normal: equal to ±|d| apart, smooth through
// touching (|d| is not), and its gradient and Hessian against differences of re-solved β and of
// the analytic gradient, apart, touching and 2 mm into each other.
TEST(EdgeEdgeTest, TheSignedRowIsSmoothThroughTouching) {
  const Scene s;
  const BodyPose pa0 = BodyPose::FromCoordinates(s.q_a);
  BodyPose pb0 = BodyPose::FromCoordinates(s.QB(0.0));
  double sampled = 0.0;
  CurveCurveExtremum apart =
      SolveCurveCurve(s.rim, pa0, s.edge, pb0, SampledClosest(s, pa0, pb0, &sampled));
  ASSERT_EQ(apart.status, ExtremalStatus::kConverged);
  // The scene's edges cross at 8°, where the parameters move 50 times faster than the poses
  // (x_q ~ 1/sin²): B turned 40° about the common normal through its point crosses them at 48°.
  const Eigen::AngleAxisd turn(0.7, (apart.p_a - apart.p_b).normalized());
  Vector7d qb0 = s.QB(0.0);
  const Eigen::Quaterniond q0(qb0[3], qb0[4], qb0[5], qb0[6]);
  qb0 = Coordinates(apart.p_b + turn * (qb0.head<3>() - apart.p_b), Eigen::Quaterniond(turn) * q0);
  pb0 = BodyPose::FromCoordinates(qb0);
  apart = SolveCurveCurve(s.rim, pa0, s.edge, pb0, SampledClosest(s, pa0, pb0, &sampled));
  ASSERT_EQ(apart.status, ExtremalStatus::kConverged);
  const Eigen::Vector3d down = (apart.p_a - apart.p_b).normalized();  // moves B towards A
  double worst_grad = 0.0, worst_hess = 0.0;
  // Pushed in, the rim's curvature along d lowers H's first pivot (d·a'' < 0): 0.2 mm in, the
  // pair is 6 times nearer its fold (det H → 0) than touching. The servo's rows stay within
  // 1e-6 m of touching; 20 µm in is checked, with differences of 2e-7 (x_q ~ 30 there).
  constexpr double h = 2e-7;
  for (const double gap : {0.003, 0.0, -2e-5}) {
    Vector7d qb = qb0;
    qb.head<3>() += down * (apart.distance - gap);
    const Vector7d qa = s.q_a;
    const BodyPose pa = BodyPose::FromCoordinates(qa), pb = BodyPose::FromCoordinates(qb);
    CurveCurveEval at;
    const CurveCurveExtremum e = SolveCurveCurve(s.rim, pa, s.edge, pb, apart.x, {}, &at);
    ASSERT_EQ(e.status, ExtremalStatus::kConverged) << "gap " << gap;
    const double angle =
        std::asin(at.a.world.C1.normalized().cross(at.b.world.C1.normalized()).norm());
    EXPECT_GT(angle, 0.5) << "gap " << gap;

    // σ: ν from B's edge towards A's where they were apart.
    Eigen::Vector3d nu;
    ASSERT_TRUE(CommonNormal(at, 1.0, &nu));
    const double sign = nu.dot(down) >= 0.0 ? 1.0 : -1.0;
    ASSERT_TRUE(CommonNormal(at, sign, &nu));
    const double beta = at.d.dot(nu);
    EXPECT_NEAR(beta, gap, 1e-12) << "gap " << gap;
    EXPECT_NEAR(std::abs(beta), e.distance, 1e-15);
    Matrix2x14 x_q;
    ASSERT_TRUE(CurveCurveJacobian(at, pa, pb, &x_q));
    const Row14 grad = EdgeEdgeGradient(at, pa, pb, nu);
    const Matrix14d hess = EdgeEdgeHessian(at, pa, pb, x_q, nu);
    Row14 fd_grad;
    Matrix14d fd_hess;
    for (int i = 0; i < 14; ++i) {
      double b[2];
      Row14 g[2];
      bool regular = true;
      ResolvedAround(s, qa, qb, i, h, e.x,
                     [&](int k, const CurveCurveExtremum&, const CurveCurveEval& ek,
                         const BodyPose& pa_k, const BodyPose& pb_k) {
                       Eigen::Vector3d nk;
                       regular = regular && CommonNormal(ek, sign, &nk);
                       b[k] = ek.d.dot(nk);
                       g[k] = EdgeEdgeGradient(ek, pa_k, pb_k, nk);
                     });
      ASSERT_TRUE(regular) << "gap " << gap << " q" << i;
      fd_grad[i] = (b[0] - b[1]) / (2 * h);
      fd_hess.col(i) = (g[0] - g[1]).transpose() / (2 * h);
    }
    EXPECT_LT(RelError(grad, fd_grad), kRelTol) << "gap " << gap;
    EXPECT_LT(RelError(hess, fd_hess), kRelTol) << "gap " << gap;
    EXPECT_LT(RelError(hess, hess.transpose()), 1e-9) << "gap " << gap;
    worst_grad = std::max(worst_grad, RelError(grad, fd_grad));
    worst_hess = std::max(worst_hess, RelError(hess, fd_hess));
  }
  std::printf("signed row, apart, touching and crossed: gradient %.1e, Hessian %.1e relative\n",
              worst_grad, worst_hess);
}

TEST(EdgeEdgeTest, ParallelEdgesHaveNoJacobian) {
  // Two straight edges on two flat faces, parallel and 1 cm apart: a continuum of closest pairs.
  const nurbs::NurbsSurface plane = nurbs::MakePlanePatch({0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0});
  const nurbs::NurbsCurve2d line = nurbs::MakePolyline2d({{0.0, 0.5}, {1.0, 0.5}});
  const BodyCurve a(&plane, &line), b(&plane, &line);
  const BodyPose pa =
      BodyPose::FromCoordinates(Coordinates({0, 0, 0}, Eigen::Quaterniond::Identity()));
  const BodyPose pb =
      BodyPose::FromCoordinates(Coordinates({0, 0, 0.01}, Eigen::Quaterniond::Identity()));
  CurveCurveEval at;
  const CurveCurveExtremum e = SolveCurveCurve(a, pa, b, pb, {0.4, 0.45}, {}, &at);
  EXPECT_NEAR(e.distance, 0.01, 1e-15);
  Matrix2x14 x_q;
  EXPECT_FALSE(CurveCurveJacobian(at, pa, pb, &x_q));
}

}  // namespace
}  // namespace tangent::contact
