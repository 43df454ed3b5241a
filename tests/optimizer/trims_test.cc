// The three trimming constraints of seed 001 §3.4: their values (the sides of the edge) and
// their analytic Jacobians, through the contact's and the edge's extremal Jacobians, against
// central differences of re-solved values, on a strongly non-orthogonal rational patch trimmed by
// a curved rational cubic, with a ball over the edge, quaternions off the unit sphere; and the
// trimmed contact (face or rim of a hole): its Jacobians, its continuity across the rim and its
// value over the hole against the ball's distance to the rim.

#include "optimizer/trims.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "nurbs/primitives.h"
#include "nurbs/trim.h"
#include "optimizer/contacts.h"
#include "optimizer/goals.h"
#include "optimizer/solver.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kH = 1e-6;
constexpr double kRadius = 0.05;

struct Scene {
  Mechanism mech;
  int patch_body, ball_body;
  // 0.3 rad between the parameter directions, a 4 mm dome, weights in [0.95, 1.05].
  nurbs::NurbsSurface patch = nurbs::MakeShearedPatch(0.3, 0.2, 0.004, true);
  nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, kRadius);
  // An S-shaped rational cubic across the domain; the material on its left.
  nurbs::NurbsCurve2d trim{nurbs::KnotVector(3, {0, 0, 0, 0, 1, 1, 1, 1}),
                           {{0.1, 0.2}, {0.35, 0.8}, {0.6, 0.1}, {0.9, 0.7}},
                           {1.0, 1.3, 0.8, 1.0}};
  Scene() {
    patch_body = mech.AddBody(Body{"patch"});
    ball_body = mech.AddBody(Body{"ball"});
  }
};

// The ball `height` above the patch point at (u, v) (along its normal), turned so that its poles
// face sideways, both bodies perturbed; quaternions scaled off the unit sphere.
Eigen::VectorXd Place(const Scene& s, const Eigen::Vector2d& uv, double height,
                      std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const nurbs::SurfacePoint at = s.patch.Evaluate(uv[0], uv[1], 1);
  const Eigen::Vector3d normal = at.S_u.cross(at.S_v).normalized();
  const Eigen::Quaterniond qa(1, 0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng));
  const Eigen::Vector3d pa(0.002 * u(rng), 0.002 * u(rng), 0.002 * u(rng));
  const Eigen::Quaterniond sideways(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond qb =
      Eigen::Quaterniond(1, 0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng)).normalized() * sideways;
  const Eigen::Vector3d pb = pa + qa.normalized() * (at.S + (kRadius + height) * normal);
  Eigen::VectorXd q(14);
  q << pa, 1.1 * qa.w(), 1.1 * qa.x(), 1.1 * qa.y(), 1.1 * qa.z(), pb, 0.9 * qb.w(), 0.9 * qb.x(),
      0.9 * qb.y(), 0.9 * qb.z();
  return q;
}

constexpr auto* Value = &testing::TermValue;  // β and ∇β at q through a term

// The term at q, seeded from sampled closest pairs, with both extrema converged and interior.
struct Placed {
  std::shared_ptr<TrimConstraintTerm> term;
  std::unique_ptr<TermState> state;
};
Placed Make(const Scene& s, TrimForm form, const Eigen::VectorXd& q) {
  std::vector<BodyPose> poses;
  s.mech.Poses(q, &poses);
  const BodyPose& pa = poses[static_cast<size_t>(s.patch_body)];
  const BodyPose& pb = poses[static_cast<size_t>(s.ball_body)];
  const Eigen::Vector4d pair = contact::ClosestSamplePair(s.patch, pa, s.ball, pb, 31);
  double best = 1e300, tau = 0.0;
  for (int k = 0; k <= 400; ++k) {
    const Eigen::Vector2d c = s.trim.Evaluate(k / 400.0, 0).C;
    const double d = (pa.Point(s.patch.Evaluate(c[0], c[1], 0).S) - pb.q.head<3>()).norm();
    if (d < best) best = d, tau = k / 400.0;
  }
  Placed p;
  p.term = MakeTrimConstraint(form, s.patch_body, &s.patch, &s.trim, s.ball_body, &s.ball, pair,
                              Eigen::Vector3d(pair[2], pair[3], tau));
  p.state = p.term->MakeState();
  Value(s.mech, *p.term, p.state.get(), q, nullptr);
  return p;
}

TEST(TrimsTest, JacobiansMatchReSolvedCentralDifferences) {
  Scene s;
  std::mt19937_64 rng(5);
  for (TrimForm form : {TrimForm::kParametric, TrimForm::kSameSurface, TrimForm::kOtherSurface}) {
    double worst = 0.0;
    for (int trial = 0; trial < 6; ++trial) {
      // Over the edge's neighbourhood, either side, touching or 2 mm apart.
      const Eigen::Vector2d uv(0.42 + 0.12 * (trial % 3), 0.38 + 0.1 * (trial / 3));
      const Eigen::VectorXd q = Place(s, uv, trial % 2 ? 0.002 : 0.0, rng);
      Placed p = Make(s, form, q);
      const auto& st = static_cast<const TrimConstraintTerm::State&>(*p.state);
      ASSERT_EQ(st.pair_ext.status, contact::ExtremalStatus::kConverged) << trial;
      ASSERT_EQ(st.edge_ext.status, contact::ExtremalStatus::kConverged) << trial;
      ASSERT_GT(st.edge[2], 0.01);
      ASSERT_LT(st.edge[2], 0.99);
      Eigen::Matrix<double, 1, 14> g;
      Value(s.mech, *p.term, p.state.get(), q, &g);
      for (int k = 0; k < 14; ++k) {
        Eigen::VectorXd qp = q, qm = q;
        qp[k] += kH;
        qm[k] -= kH;
        const double fd = (Value(s.mech, *p.term, p.state.get(), qp, nullptr) -
                           Value(s.mech, *p.term, p.state.get(), qm, nullptr)) /
                          (2 * kH);
        const double scale = std::max(1.0, g.cwiseAbs().maxCoeff());
        worst = std::max(worst, std::abs(fd - g[k]) / scale);
        EXPECT_NEAR(fd, g[k], 1e-6 * scale) << ToString(form) << " trial " << trial << " q" << k;
      }
    }
    std::printf("%s: largest |J − FD| / max(1, |J|∞) over 6 poses x 14 coordinates: %.2e\n",
                ToString(form), worst);
  }
}

TEST(TrimsTest, TheSignSaysWhichSideOfTheEdgeTheContactIsOn) {
  // The ball over a point left of the trim curve (material) and over one right of it: the three
  // forms agree on the side, and the parametric one equals the domain normal's projection.
  Scene s;
  std::mt19937_64 rng(9);
  const nurbs::CurvePoint<2> c = s.trim.Evaluate(0.5, 1);
  const Eigen::Vector2d left(-c.C1[1], c.C1[0]);
  for (const double side : {1.0, -1.0}) {
    const Eigen::Vector2d uv = c.C + side * 0.06 * left.normalized();
    const Eigen::VectorXd q = Place(s, uv, 0.001, rng);
    for (TrimForm form : {TrimForm::kParametric, TrimForm::kSameSurface, TrimForm::kOtherSurface}) {
      Placed p = Make(s, form, q);
      const double r = Value(s.mech, *p.term, p.state.get(), q, nullptr);
      EXPECT_GT(side * r, 0.0) << ToString(form) << " side " << side;
    }
  }
}

TEST(TrimsTest, AUnilateralTrimKeepsTheContactOnTheMaterialAndABilateralOneOnTheEdge) {
  // The patch is the ground; the ball touches it (a floating contact, beta = 0) and a goal pulls
  // its centre across the trim edge onto the trimmed-away side. Without the trim the contact
  // follows the goal off the material; with it (r >= 0) the contact stops on the edge; with the
  // bilateral form (r = 0) it is held on the edge from a start on the material.
  Mechanism mech;
  Scene s;
  const int patch = mech.AddBody(Body{"patch", true});
  const int ball = mech.AddBody(Body{"ball"});
  const nurbs::CurvePoint<2> c = s.trim.Evaluate(0.5, 1);
  const Eigen::Vector2d left = Eigen::Vector2d(-c.C1[1], c.C1[0]).normalized();
  // The reference material: left of the trim, closed by a polyline round the upper left.
  const nurbs::NurbsCurve2d closing(nurbs::KnotVector(1, {0, 0, 1, 2, 3, 3}),
                                    {{0.9, 0.7}, {0.9, 0.95}, {0.1, 0.95}, {0.1, 0.2}});
  const nurbs::TrimmedDomain material({0, 0}, {1, 1}, nurbs::TrimLoop{{s.trim, closing}}, {});
  auto centre_over = [&](const Eigen::Vector2d& uv) {
    const nurbs::SurfacePoint at = s.patch.Evaluate(uv[0], uv[1], 1);
    return Eigen::Vector3d(at.S + kRadius * at.S_u.cross(at.S_v).normalized());
  };
  const Eigen::Vector2d start_uv = c.C + 0.08 * left, target_uv = c.C - 0.15 * left;
  const Eigen::Quaterniond sideways(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  Eigen::VectorXd q0(7);
  q0 << centre_over(start_uv), sideways.w(), sideways.x(), sideways.y(), sideways.z();
  std::vector<BodyPose> poses;
  mech.Poses(q0, &poses);
  const Eigen::Vector4d pair = contact::ClosestSamplePair(
      s.patch, poses[static_cast<size_t>(patch)], s.ball, poses[static_cast<size_t>(ball)], 31);
  auto solve = [&](int trim) {  // 0: none, 1: unilateral, 2: bilateral
    Problem p(mech);
    const auto touch = MakeSurfaceContact(patch, &s.patch, ball, &s.ball, pair);
    p.AddEquality(touch);
    const auto t = MakeTrimConstraint(TrimForm::kParametric, patch, &s.patch, &s.trim, ball,
                                      &s.ball, pair, Eigen::Vector3d(pair[2], pair[3], 0.5));
    if (trim == 1) p.AddInequality(t);
    if (trim == 2) p.AddEquality(t);
    p.AddObjective(MakePositionGoal({ball, Eigen::Vector3d::Zero()}, centre_over(target_uv)), 1.0);
    SolverOptions o;
    o.max_iterations = 200;
    Solver solver(p, o);
    Eigen::VectorXd q = q0;
    const SolveStats st = solver.Solve(&q);
    EXPECT_TRUE(st.converged) << trim;
    EXPECT_LE(st.max_violation, 1e-10) << trim;
    // Where the contact ended: the pair's parameters on the patch.
    return Eigen::Vector2d(solver.data().Of(*touch).extremum().u.head<2>());
  };
  const Eigen::Vector2d free = solve(0), kept = solve(1), held = solve(2);
  const double d_free = material.Nearest(free).signed_distance;
  const double d_kept = material.Nearest(kept).signed_distance;
  const double d_held = material.Nearest(held).signed_distance;
  std::printf(
      "contact's parametric distance to the edge: free %.3g, unilateral %.3g, "
      "bilateral %.3g\n",
      d_free, d_kept, d_held);
  EXPECT_LT(d_free, -0.05);           // without the trim: well inside the trimmed-away side
  EXPECT_GE(d_kept, -1e-9);           // the unilateral trim: on the material ...
  EXPECT_LT(std::abs(d_kept), 1e-9);  // ... at its edge, where the goal presses it
  EXPECT_LT(std::abs(d_held), 1e-9);
}

// A plate (the sheared rational patch) with a round hole in its domain, and the ball.
struct HoleScene : Scene {
  nurbs::TrimmedDomain plate{{0, 0},
                             {1, 1},
                             std::nullopt,
                             {nurbs::TrimLoop{{nurbs::MakeCircle2d({0.5, 0.5}, 0.2, true)}}}};
};

// The ball's centre over the patch point (u, v) at `height` above it (along the normal),
// turned sideways, both bodies as Place does but without the random tilt.
Eigen::VectorXd Over(const Scene& s, const Eigen::Vector2d& uv, double height) {
  const nurbs::SurfacePoint at = s.patch.Evaluate(uv[0], uv[1], 1);
  const Eigen::Vector3d normal = at.S_u.cross(at.S_v).normalized();
  const Eigen::Quaterniond sideways(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  Eigen::VectorXd q(14);
  q << 0, 0, 0, 1, 0, 0, 0, at.S + height * normal, sideways.w(), sideways.x(), sideways.y(),
      sideways.z();
  return q;
}

TEST(TrimsTest, ATrimmedContactMeasuresTheRimOverAHoleWithExactJacobians) {
  HoleScene s;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst[2] = {0.0, 0.0}, worst_h[2] = {0.0, 0.0};
  for (int trial = 0; trial < 12; ++trial) {
    // Over the hole near its rim (the edge form) or over the plate (the face form), well away
    // from the switch so that ±h stays on one side.
    const bool over_hole = trial % 2 == 0;
    const double angle = 2 * M_PI * (trial + 0.3 * u(rng)) / 12;
    const double radius = over_hole ? 0.15 + 0.03 * u(rng) : 0.3 + 0.05 * u(rng);
    const Eigen::Vector2d uv =
        Eigen::Vector2d(0.5, 0.5) + radius * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    Eigen::VectorXd q = Over(s, uv, kRadius + 0.003 * u(rng));
    q.segment<4>(3) *= 1.1;  // quaternions off the unit sphere
    q.segment<4>(10) *= 0.9;
    std::vector<BodyPose> poses;
    s.mech.Poses(q, &poses);
    const auto term = std::make_shared<TrimmedContactTerm>(
        s.patch_body, &s.patch, &s.plate, s.ball_body, &s.ball,
        contact::ClosestSamplePair(s.patch, poses[0], s.ball, poses[1], 31));
    const auto state = term->MakeState();
    Eigen::Matrix<double, 1, 14> g;
    const double beta = Value(s.mech, *term, state.get(), q, &g);
    const auto& st = static_cast<const TrimmedContactTerm::State&>(*state);
    ASSERT_EQ(st.on_edge, over_hole) << trial;
    EXPECT_LT(std::abs(beta), 0.02);
    const Eigen::Matrix<double, 1, 14> fd =
        testing::ValueDifferences(s.mech, *term, state.get(), q, kH);
    for (int k = 0; k < 14; ++k) {
      worst[over_hole] = std::max(worst[over_hole], std::abs(fd[k] - g[k]));
      EXPECT_NEAR(fd[k], g[k], 1e-7)
          << (over_hole ? "edge" : "face") << " trial " << trial << " q" << k;
    }
    // The Hessian (the face's through SurfaceContactTerm, the edge's own) against central
    // differences of the analytic gradient, weighted.
    const Eigen::Matrix<double, 14, 1> err =
        testing::HessianRowErrors(s.mech, *term, state.get(), q, 0.7, kH);
    for (int k = 0; k < 14; ++k) {
      worst_h[over_hole] = std::max(worst_h[over_hole], err[k]);
      EXPECT_LT(err[k], 1e-5) << (over_hole ? "edge" : "face") << " trial " << trial
                              << " Hessian row " << k;
    }
  }
  std::printf(
      "largest |J − FD|: face %.2e, edge %.2e; largest |H − FD(J)| (relative): face "
      "%.2e, edge %.2e\n",
      worst[0], worst[1], worst_h[0], worst_h[1]);
}

TEST(TrimsTest, ATrimmedContactIsContinuousAcrossTheRim) {
  // The ball slid in 2e-5 m steps from over the plate to over the hole and back: β is a distance,
  // 1-Lipschitz in the ball's translation, so no step may change it by more than the step —
  // across the switches from the face to the edge too.
  HoleScene s;
  const Eigen::Vector2d from(0.5, 0.88), to(0.5, 0.55);
  const Eigen::VectorXd q0 = Over(s, from, kRadius + 0.001), q1 = Over(s, to, kRadius + 0.001);
  std::vector<BodyPose> poses;
  s.mech.Poses(q0, &poses);
  const auto term = std::make_shared<TrimmedContactTerm>(
      s.patch_body, &s.patch, &s.plate, s.ball_body, &s.ball,
      contact::ClosestSamplePair(s.patch, poses[0], s.ball, poses[1], 31));
  const auto state = term->MakeState();
  const double length = (q1.segment<3>(7) - q0.segment<3>(7)).norm();
  const int n = static_cast<int>(length / 2e-5);
  double worst = 0.0, prev = Value(s.mech, *term, state.get(), q0, nullptr), lowest = prev;
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 1; k <= n; ++k) {
      const double t = pass == 0 ? static_cast<double>(k) / n : 1.0 - static_cast<double>(k) / n;
      Eigen::VectorXd q = q0;
      q.segment<3>(7) = (1 - t) * q0.segment<3>(7) + t * q1.segment<3>(7);
      const double beta = Value(s.mech, *term, state.get(), q, nullptr);
      const double step = length / n;
      worst = std::max(worst, std::abs(beta - prev) / step);
      lowest = std::min(lowest, beta);
      prev = beta;
    }
  }
  const auto& st = static_cast<const TrimmedContactTerm::State&>(*state);
  Value(s.mech, *term, state.get(), q1, nullptr);
  const double over_hole = Value(s.mech, *term, state.get(), q1, nullptr);
  std::printf(
      "%d steps each way, %lld switches, largest |dbeta| / step %.4f, beta over the "
      "plate %.4f, over the hole %.4f\n",
      n, static_cast<long long>(st.switches), worst, lowest, over_hole);
  EXPECT_GE(st.switches, 2);
  EXPECT_LE(worst, 1.0 + 1e-6);
  // Over the hole the nearest material is the rim: β is the ball's distance to the rim curve,
  // against a dense sampling of it (10^5 points: its own error ≤ 1e-9 m here).
  std::vector<BodyPose> at_end;
  s.mech.Poses(q1, &at_end);
  double nearest = 1e300;
  const nurbs::NurbsCurve2d& rim = s.plate.loops()[0].curves[0];
  for (int k = 0; k <= 100000; ++k) {
    const Eigen::Vector2d c = rim.Evaluate(k / 100000.0, 0).C;
    nearest = std::min(
        nearest,
        (at_end[0].Point(s.patch.Evaluate(c[0], c[1], 0).S) - at_end[1].q.head<3>()).norm());
  }
  EXPECT_NEAR(over_hole, nearest - kRadius, 1e-8);
}

}  // namespace
}  // namespace tangent::optimizer
