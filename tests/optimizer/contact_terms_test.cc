// Surface–surface contact and point-on-surface terms: β and its analytic Jacobian and weighted
// Hessian (through the tracked extremal parameters and the closed-form u_q) against central
// finite differences, at seeded random poses near contact, quaternions off the unit sphere.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "nurbs/primitives.h"
#include "optimizer/clearance_guard.h"
#include "optimizer/contacts.h"
#include "optimizer/goals.h"
#include "optimizer/solver.h"
#include "testing/contact_scenes.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kH = 1e-6;

struct Scene {
  Mechanism mech;
  int a, b;
  nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, 0.05);
  nurbs::NurbsSurface patch = nurbs::MakeShearedPatch(0.3, 0.2, 0.01, true);
  Scene() {
    a = mech.AddBody(Body{"ball"});
    b = mech.AddBody(Body{"patch"});
  }
};

// Poses: the patch near the identity, the ball's centre `gap` + radius above the patch middle
// (so β ≈ gap), both perturbed; quaternions scaled off the unit sphere.
Eigen::VectorXd NearContact(const Scene& s, double gap, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const nurbs::SurfacePoint mid = s.patch.Evaluate(0.5, 0.5, 1);
  const Eigen::Vector3d normal = mid.S_u.cross(mid.S_v).normalized();
  Eigen::VectorXd q(14);
  const Eigen::Quaterniond qa = Eigen::Quaterniond(1, 0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng));
  const Eigen::Quaterniond qb = Eigen::Quaterniond(1, 0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng));
  const Eigen::Vector3d pb(0.002 * u(rng), 0.002 * u(rng), 0.002 * u(rng));
  const Eigen::Vector3d pa = pb + qb.normalized() * (mid.S + (0.05 + gap) * normal) +
                             Eigen::Vector3d(0.01 * u(rng), 0.01 * u(rng), 0.0);
  q << pa, 1.2 * qa.coeffs()[3], 1.2 * qa.x(), 1.2 * qa.y(), 1.2 * qa.z(), pb, 0.9 * qb.w(),
      0.9 * qb.x(), 0.9 * qb.y(), 0.9 * qb.z();
  return q;
}

// The extremum a contact term's state holds.
const contact::SurfaceSurfaceExtremum& Extremum(const SurfaceContactTerm&, TermState* st) {
  return static_cast<SurfaceContactTerm::State*>(st)->extremum();
}
const contact::PointSurfaceExtremum& Extremum(const PointOnSurfaceTerm&, TermState* st) {
  return static_cast<PointOnSurfaceTerm::State*>(st)->extremum();
}

constexpr auto* Value = &testing::TermValue;  // β and ∇β at q through a term

void CheckDerivatives(const Mechanism& m, const Term& t, TermState* st, const Eigen::VectorXd& q,
                      double tol_j, double tol_h) {
  Eigen::Matrix<double, 1, 14> g;
  Value(m, t, st, q, &g);
  const double w = 0.7;
  const Eigen::Matrix<double, 14, 14> H = testing::TermHessianAt(m, t, st, q, w);
  const Eigen::Matrix<double, 14, 14> fd = testing::GradientDifferences(m, t, st, q, w, kH);
  for (int k = 0; k < 14; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += kH;
    qm[k] -= kH;
    const double fp = Value(m, t, st, qp, nullptr), fm = Value(m, t, st, qm, nullptr);
    EXPECT_NEAR((fp - fm) / (2 * kH), g[k], tol_j) << t.name() << " coordinate " << k;
    EXPECT_LT((fd.row(k) - H.row(k)).cwiseAbs().maxCoeff(), tol_h)
        << t.name() << " Hessian row " << k;
  }
  Value(m, t, st, q, nullptr);  // Leave the term at q.
}

TEST(ContactTermsTest, SurfaceContactDerivativesMatchFiniteDifferences) {
  Scene s;
  std::mt19937_64 rng(41);
  for (double gap : {0.0, 0.004, -0.002}) {  // touching, apart, interpenetrating
    for (int trial = 0; trial < 4; ++trial) {
      const Eigen::VectorXd q = NearContact(s, gap, rng);
      std::vector<BodyPose> poses;
      s.mech.Poses(q, &poses);
      const auto term = MakeSurfaceContact(
          s.a, &s.sphere, s.b, &s.patch,
          contact::ClosestSamplePair(s.sphere, poses[static_cast<size_t>(s.a)], s.patch,
                                     poses[static_cast<size_t>(s.b)], 23));
      const std::unique_ptr<TermState> st = term->MakeState();
      const double beta = Value(s.mech, *term, st.get(), q, nullptr);
      ASSERT_EQ(Extremum(*term, st.get()).status, contact::ExtremalStatus::kConverged);
      EXPECT_NEAR(beta, gap, 0.015);  // the bump and the offsets move it by millimetres
      CheckDerivatives(s.mech, *term, st.get(), q, 1e-8, 2e-6);
    }
  }
}

// Two unit squares, f beside and above g, closest corner to corner: β is the distance between
// the corners and every parameter is held, so the value, the Jacobian and the Hessian are
// exact there (no free parameter moves with q). An edge against a face (a tipped cylinder's rim
// over g): the rim's angle and g's two parameters move with q, through the restricted u_q.
TEST(ContactTermsTest, BoundaryContactDerivativesMatchFiniteDifferences) {
  Mechanism mech;
  const int a = mech.AddBody(Body{"upper"}), b = mech.AddBody(Body{"lower"});
  const nurbs::NurbsSurface square = nurbs::MakePlanePatch({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    // f turned over (facing g) and perturbed.
    const Eigen::Quaterniond qa =
        Eigen::Quaterniond(1, 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng)) *
        Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()));
    const Eigen::Quaterniond qb(1, 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng));
    Eigen::VectorXd q(14);
    q << 1.3 + 0.05 * u(rng), 2.2 + 0.05 * u(rng), 0.4 + 0.05 * u(rng), 1.1 * qa.w(), 1.1 * qa.x(),
        1.1 * qa.y(), 1.1 * qa.z(), 0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng), 0.95 * qb.w(),
        0.95 * qb.x(), 0.95 * qb.y(), 0.95 * qb.z();
    const auto term = MakeSurfaceContact(a, &square, b, &square, {0.2, 0.2, 0.8, 0.8});
    const std::unique_ptr<TermState> st = term->MakeState();
    const double beta = Value(mech, *term, st.get(), q, nullptr);
    const auto& e = Extremum(*term, st.get());
    ASSERT_EQ(e.status, contact::ExtremalStatus::kAtBoundary);
    ASSERT_TRUE(e.at_bound[0] && e.at_bound[1] && e.at_bound[2] && e.at_bound[3]);
    EXPECT_NEAR(beta, (e.p_f - e.p_g).norm(), 1e-15);
    CheckDerivatives(mech, *term, st.get(), q, 1e-8, 2e-6);
  }
  // Edge against face: a cylinder (radius 0.2) tipped 0.3 rad about x, its lowest rim point
  // 0.1 above g's middle.
  const nurbs::NurbsSurface cylinder = nurbs::MakeCylinder(0.2, 1.0);
  const Eigen::Quaterniond tip(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  Eigen::VectorXd q(14);
  q << 0.5, 0.5, 0.1 + 0.2 * std::sin(0.3), tip.w(), tip.x(), tip.y(), tip.z(), 0, 0, 0, 1, 0, 0, 0;
  std::vector<BodyPose> poses;
  mech.Poses(q, &poses);
  const auto term =
      MakeSurfaceContact(a, &cylinder, b, &square,
                         contact::ClosestSamplePair(cylinder, poses[0], square, poses[1], 16));
  const std::unique_ptr<TermState> st = term->MakeState();
  const double beta = Value(mech, *term, st.get(), q, nullptr);
  ASSERT_EQ(Extremum(*term, st.get()).status, contact::ExtremalStatus::kAtBoundary);
  EXPECT_NEAR(beta, 0.1, 1e-14);
  CheckDerivatives(mech, *term, st.get(), q, 1e-8, 2e-6);
}

// The term follows its contact with contact/'s tracker; a jump the tracker cannot follow is
// reported `lost`, counted, and answered by a full extremal solve: β afterwards equals a fresh
// solve's, never a silently wrong extremum.
// β at configuration q by a full extremal solve from the term's current parameters: what the
// tracked β must equal.
double FullSolveBeta(const Scene& s, const SurfaceContactTerm::State& st,
                     const Eigen::VectorXd& q) {
  std::vector<BodyPose> poses;
  s.mech.Poses(q, &poses);
  return contact::SolveSurfaceSurface(s.sphere, poses[static_cast<size_t>(s.a)], s.patch,
                                      poses[static_cast<size_t>(s.b)], st.extremum().u)
      .beta;
}

TEST(ContactTermsTest, TrackerStatesAndALostStepAreDefinedEvents) {
  Scene s;
  std::mt19937_64 rng(44);
  Eigen::VectorXd q = NearContact(s, 0.004, rng);
  std::vector<BodyPose> poses;
  s.mech.Poses(q, &poses);
  const auto term =
      MakeSurfaceContact(s.a, &s.sphere, s.b, &s.patch,
                         contact::ClosestSamplePair(s.sphere, poses[static_cast<size_t>(s.a)],
                                                    s.patch, poses[static_cast<size_t>(s.b)], 23));
  const std::unique_ptr<TermState> st_ptr = term->MakeState();
  auto& st = static_cast<SurfaceContactTerm::State&>(*st_ptr);
  Value(s.mech, *term, &st, q, nullptr);  // the first evaluation solves and starts tracking
  EXPECT_EQ(st.solves, 1);
  EXPECT_TRUE(st.tracking);
  // Small motions: tracked, and β equal to a full solve's to 1e-14.
  for (int k = 0; k < 50; ++k) {
    q[0] += 2e-5;
    q[11] += 1e-4;
    const double beta = Value(s.mech, *term, &st, q, nullptr);
    EXPECT_NEAR(beta, FullSolveBeta(s, st, q), 1e-14) << "step " << k;
  }
  EXPECT_EQ(st.track_status, contact::TrackStatus::kTracked);
  EXPECT_EQ(st.tracked_steps, 50);
  EXPECT_EQ(st.solves, 1);
  // Jumps the tracker cannot follow in one step: the ball turned about three axes by 1–2.5 rad
  // in one evaluation. Each is reported (`lost`, or `singular` where the prediction lands on a
  // pole), counted, and answered by a full solve from the last parameters: β is a fresh
  // solve's, bit for bit.
  int64_t lost = 0, solves = st.solves;
  for (const Eigen::Vector3d& axis :
       {Eigen::Vector3d(0.3, 1, 0.2), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0.2, 1)}) {
    for (double angle : {1.0, 2.5}) {
      const Eigen::Quaterniond turn(Eigen::AngleAxisd(angle, axis.normalized()));
      const Eigen::Quaterniond qa(q[3], q[4], q[5], q[6]);
      const Eigen::Quaterniond moved = turn * qa;
      q.segment<4>(3) << moved.w(), moved.x(), moved.y(), moved.z();
      const Eigen::Vector4d before = st.extremum().u;
      const double beta = Value(s.mech, *term, &st, q, nullptr);
      if (st.track_status == contact::TrackStatus::kTracked && st.solves == solves) continue;
      EXPECT_EQ(st.solves, solves + 1);
      solves = st.solves;
      lost += st.track_status == contact::TrackStatus::kLost;
      s.mech.Poses(q, &poses);
      const contact::SurfaceSurfaceExtremum fresh =
          contact::SolveSurfaceSurface(s.sphere, poses[static_cast<size_t>(s.a)], s.patch,
                                       poses[static_cast<size_t>(s.b)], before);
      EXPECT_EQ(beta, fresh.beta) << "axis " << axis.transpose() << " angle " << angle;
    }
  }
  EXPECT_EQ(st.lost, lost);
  EXPECT_GT(lost, 0);
  EXPECT_GT(st.solves, 3);
  EXPECT_TRUE(st.tracking);  // restarted from the solve
}

TEST(ContactTermsTest, PointOnSurfaceDerivativesMatchFiniteDifferences) {
  Scene s;
  std::mt19937_64 rng(42);
  for (double gap : {0.0, 0.01, -0.003}) {
    for (int trial = 0; trial < 4; ++trial) {
      const Eigen::VectorXd q = NearContact(s, gap, rng);
      // The ball's attachment point: its point nearest the patch (gap above it).
      std::vector<BodyPose> poses;
      s.mech.Poses(q, &poses);
      const nurbs::SurfacePoint mid = s.patch.Evaluate(0.5, 0.5, 1);
      const Eigen::Vector3d n_W =
          poses[static_cast<size_t>(s.b)].R_WB * mid.S_u.cross(mid.S_v).normalized();
      const BodyPose& ball = poses[static_cast<size_t>(s.a)];
      const Eigen::Vector3d low_W = ball.q.head<3>() - 0.05 * n_W;
      const Attachment at{s.a, ball.R_WB.transpose() * (low_W - ball.q.head<3>())};
      const auto term = MakePointOnSurface(at, s.b, &s.patch, {0.5, 0.5});
      const std::unique_ptr<TermState> st = term->MakeState();
      Value(s.mech, *term, st.get(), q, nullptr);
      ASSERT_EQ(Extremum(*term, st.get()).status, contact::ExtremalStatus::kConverged);
      CheckDerivatives(s.mech, *term, st.get(), q, 1e-8, 2e-6);
    }
  }
}

TEST(ContactTermsTest, BadInputIsRejectedWithAMessage) {
  Scene s;
  try {
    MakeSurfaceContact(s.a, &s.sphere, s.a, &s.patch, {0.5, 0.5, 0.5, 0.5});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "surface contact: both surfaces on one body");
  }
  try {
    MakeSurfaceContact(s.a, nullptr, s.b, &s.patch, {0.5, 0.5, 0.5, 0.5});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "surface contact: null surface");
  }
  try {
    MakePointOnSurface({s.a, {0, 0, 0}}, s.b, &s.patch, {std::nan(""), 0.5});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "point on surface: non-finite seed");
  }
  for (int steps : {-1, 4}) {
    try {
      MakeSurfaceContact(s.a, &s.sphere, s.b, &s.patch, {0.5, 0.5, 0.5, 0.5},
                         ContactTracking{steps, 1e-12});
      ADD_FAILURE();
    } catch (const std::invalid_argument& e) {
      EXPECT_STREQ(e.what(), "surface contact: corrector_steps must be 0 to 3");
    }
  }
  for (double accept : {1e-13, std::nan("")}) {
    try {
      MakeSurfaceContact(s.a, &s.sphere, s.b, &s.patch, {0.5, 0.5, 0.5, 0.5},
                         ContactTracking{1, accept});
      ADD_FAILURE();
    } catch (const std::invalid_argument& e) {
      EXPECT_STREQ(e.what(), "surface contact: accept_residual must be at least 1e-12");
    }
  }
}

// The tracking settings bench/speed_error sweeps: the default is exact (β a full solve's to
// 1e-14 at every step); with the tracker's point accepted as it stands and no corrector, β is
// the first-order prediction's, off by about the predictor's residual, and no full solve runs.
TEST(ContactTermsTest, LooserTrackingTradesExactnessForSolves) {
  Scene s;
  std::mt19937_64 rng(44);
  const Eigen::VectorXd q0 = NearContact(s, 0.004, rng);
  std::vector<BodyPose> poses;
  s.mech.Poses(q0, &poses);
  const Eigen::Vector4d seed = contact::ClosestSamplePair(
      s.sphere, poses[static_cast<size_t>(s.a)], s.patch, poses[static_cast<size_t>(s.b)], 23);
  double worst[2] = {0, 0};
  int64_t solves[2] = {0, 0};
  const ContactTracking settings[2] = {ContactTracking{}, ContactTracking{0, 1e-3}};
  for (int m = 0; m < 2; ++m) {
    const auto term = MakeSurfaceContact(s.a, &s.sphere, s.b, &s.patch, seed, settings[m]);
    const std::unique_ptr<TermState> st_ptr = term->MakeState();
    auto& st = static_cast<SurfaceContactTerm::State&>(*st_ptr);
    Eigen::VectorXd q = q0;
    Value(s.mech, *term, &st, q, nullptr);
    for (int k = 0; k < 50; ++k) {
      q[0] += 1e-4;
      q[11] += 5e-4;
      const double beta = Value(s.mech, *term, &st, q, nullptr);
      worst[m] = std::max(worst[m], std::abs(beta - FullSolveBeta(s, st, q)));
    }
    solves[m] = st.solves;
  }
  std::printf("beta error: exact %.1e (%lld solves), tracked without corrector %.1e (%lld)\n",
              worst[0], static_cast<long long>(solves[0]), worst[1],
              static_cast<long long>(solves[1]));
  EXPECT_LT(worst[0], 1e-14);
  EXPECT_GT(worst[1], 1e-12);  // the prediction's error shows
  EXPECT_LT(worst[1], 1e-6);   // and stays second order in a 0.1 mm step
  EXPECT_LE(solves[1], solves[0]);
}

// A 2 mm ball over a sheet with two ridges (crests at x = 5 and 15 mm, 3 mm high). At A the
// ball hangs over the valley between them, left of centre: its contact is the left ridge's
// minimum (4.4 mm apart), and the right ridge has a minimum of its own, farther (5.9 mm). At B
// the ball is past the right ridge, where the left ridge's minimum no longer exists.
struct Ridges {
  static std::vector<std::vector<double>> Heights() {
    std::vector<std::vector<double>> heights(13, std::vector<double>(4));
    for (int i = 0; i < 13; ++i) {
      const double x = 0.02 * i / 12.0;
      for (double& h : heights[static_cast<size_t>(i)]) {
        h = 1.5e-3 * (1.0 - std::cos(2.0 * std::numbers::pi * x / 0.01));
      }
    }
    return heights;
  }
  static Eigen::VectorXd At(double x, double z) {
    Eigen::VectorXd q(14);
    const double c = std::sqrt(0.5);  // the ball turned 90° about x: its poles off the contact
    q << x, 0, z, c, c, 0, 0, 0, 0, 0, 1, 0, 0, 0;
    return q;
  }
  Ridges() {
    a = mech.AddBody(Body{"ball"});
    b = mech.AddBody(Body{"sheet"});
    std::vector<BodyPose> poses;
    mech.Poses(qA, &poses);
    term = MakeSurfaceContact(a, &ball, b, &sheet,
                              contact::ClosestSamplePair(ball, poses[static_cast<size_t>(a)], sheet,
                                                         poses[static_cast<size_t>(b)], 33));
  }
  const nurbs::NurbsSurface sheet = nurbs::MakeHeightGridPatch(0.0, -0.005, 0.02, 0.01, Heights());
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 0.002);
  Mechanism mech;
  int a = 0, b = 0;
  const Eigen::VectorXd qA = At(0.0085, 0.008), qB = At(0.019, 0.004);
  std::shared_ptr<SurfaceContactTerm> term;
};

TEST(ContactTermsTest, ARewoundStateSolvesFromTheAnchorNotFromARejectedTrial) {
  // The solver's line search evaluates trial points and halves the step when one is rejected
  // (Solver::Solve). A trial far along a step can carry a contact onto another branch of its
  // pair; the next, shorter trial must start from the base point's contact, not from there.
  // Scene: Ridges; B is a trial that carries the ball past the right ridge.
  const Ridges r;
  const Mechanism& mech = r.mech;
  const auto& term = r.term;
  const Eigen::VectorXd& qA = r.qA;
  const Eigen::VectorXd& qB = r.qB;
  // The left flank's contact at A, and the right flank's minimum there (seeded beside it).
  const std::unique_ptr<TermState> fresh = term->MakeState();
  const double beta_A = Value(mech, *term, fresh.get(), qA, nullptr);
  const Eigen::Vector4d u_A = Extremum(*term, fresh.get()).u;
  ASSERT_EQ(Extremum(*term, fresh.get()).status, contact::ExtremalStatus::kConverged);
  ASSERT_LT(u_A[2], 0.5) << "the left flank (x < 10 mm)";

  for (const bool rewind : {true, false}) {
    const std::unique_ptr<TermState> st = term->MakeState();
    Value(mech, *term, st.get(), qA, nullptr);
    st->Anchor(0);
    Value(mech, *term, st.get(), qB, nullptr);  // the rejected trial
    const Eigen::Vector4d u_B = Extremum(*term, st.get()).u;
    if (rewind) st->Rewind(0);
    const double beta = Value(mech, *term, st.get(), qA, nullptr);  // a shorter trial: here A
    const Eigen::Vector4d u = Extremum(*term, st.get()).u;
    if (rewind) {
      // Rewound: the anchor's contact, bit for bit a fresh evaluation's.
      EXPECT_EQ(beta, beta_A);
      EXPECT_EQ(u, u_A);
    } else {
      // Not rewound (what the line search did before): the trial took the contact over the
      // ridge, and back at A it stays on the right flank's minimum, farther than the ball's
      // real contact. The scene would be held by the wrong side of the valley.
      EXPECT_GT(u_B[2], 0.5) << "the trial's contact is right of the valley";
      EXPECT_GT(u[2], 0.5);
      EXPECT_GT(beta, beta_A + 1e-4);
    }
  }
  // The two anchors are kept apart: A in one (the solve's best iterate), a later iterate B in
  // the other (a line search's base point); an unconverged solve that returns A finds A's
  // contact there, and the other anchor still holds B's.
  const std::unique_ptr<TermState> st = term->MakeState();
  Value(mech, *term, st.get(), qA, nullptr);
  st->Anchor(1);
  Value(mech, *term, st.get(), qB, nullptr);
  const Eigen::Vector4d u_B = Extremum(*term, st.get()).u;
  st->Anchor(0);
  st->Rewind(1);
  EXPECT_EQ(Value(mech, *term, st.get(), qA, nullptr), beta_A);
  EXPECT_EQ(Extremum(*term, st.get()).u, u_A);
  st->Rewind(0);
  Value(mech, *term, st.get(), qB, nullptr);
  EXPECT_EQ(Extremum(*term, st.get()).u, u_B);
}

TEST(ContactTermsTest, AnUnconvergedSolveReturnsItsBestIterateWithThatIterateContacts) {
  // An unconverged solve returns its best iterate (Solver::Solve), here its start A: the ball,
  // marked for the return bound (ClearanceGuard::BoundReturn, 1 mm), was carried 10 mm to B by
  // its one Newton step. Its contact there is the right ridge's; back at A it must be the left
  // ridge's again, as it was at A, not the right ridge's minimum re-solved from B's.
  Ridges r;
  const std::unique_ptr<TermState> fresh = r.term->MakeState();
  const double beta_A = Value(r.mech, *r.term, fresh.get(), r.qA, nullptr);
  Problem p(r.mech);
  p.AddObjective(PositionGoal({r.a, {0, 0, 0}}, r.qB.head<3>()), 1.0);
  p.AddInequality(r.term);
  ClearanceGuard guard;
  guard.Configure(r.mech, {}, {0.002, 0.02});
  SolverOptions options;
  options.max_iterations = 1;
  options.max_solve_motion = 1e-3;
  Solver solver(p, options);
  solver.set_clearance_guard(&guard);
  solver.set_motion_marker(
      [](void* g) {
        static_cast<ClearanceGuard*>(g)->BoundReturn(0, true);
        return false;
      },
      &guard);
  Eigen::VectorXd q = r.qA;
  const SolveStats st = solver.Solve(&q);
  EXPECT_FALSE(st.converged);
  EXPECT_EQ(q, r.qA);
  const auto& contact = solver.data().Of(*r.term);
  EXPECT_LT(contact.extremum().u[2], 0.5) << "the left ridge's contact";
  EXPECT_EQ(contact.extremum().beta, beta_A);
  // Its one step did reach B, past the right ridge: unmarked, the solve returns it.
  guard.ClearReturnBounds();
  solver.set_motion_marker(nullptr, nullptr);
  q = r.qA;
  solver.Solve(&q);
  EXPECT_GT(q[0], 0.018);
  EXPECT_GT(solver.data().Of(*r.term).extremum().u[2], 0.5) << "the right ridge's contact";
}

}  // namespace
}  // namespace tangent::optimizer
