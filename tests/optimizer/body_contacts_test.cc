// A contact slot between two multi-face bodies (optimizer/body_contacts.h): moved to a face
// pair, it is that face pair's own term (a trimmed contact over a hole's rim or on the plate, or
// an untrimmed surface contact) in its body order, bit for bit, with both faces' bodies either
// side; its Jacobian and Hessian against central differences; moving it allocates nothing; it
// refuses face pairs that are not its bodies'.

#include "optimizer/body_contacts.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "nurbs/primitives.h"
#include "nurbs/trim.h"
#include "optimizer/contacts.h"
#include "optimizer/trims.h"
#include "testing/alloc_counter.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kH = 1e-6;
constexpr double kRadius = 0.05;

// A plate with two faces (the sheared rational patch with a round hole in its domain, id 0; the
// same patch untrimmed, id 1) and a ball with one face (id 5), in a mechanism of two bodies,
// the plate first or second.
struct TwoBodies {
  explicit TwoBodies(bool plate_first) {
    plate = mech.AddBody(Body{plate_first ? "plate" : "ball"});
    ball = mech.AddBody(Body{plate_first ? "ball" : "plate"});
    if (!plate_first) std::swap(plate, ball);
  }
  Mechanism mech;
  int plate = 0, ball = 1;
  nurbs::NurbsSurface patch = nurbs::MakeShearedPatch(0.3, 0.2, 0.004, true);
  nurbs::NurbsSurface sphere = nurbs::MakeSphere({0, 0, 0}, kRadius);
  nurbs::TrimmedDomain holed{{0, 0},
                             {1, 1},
                             std::nullopt,
                             {nurbs::TrimLoop{{nurbs::MakeCircle2d({0.5, 0.5}, 0.2, true)}}}};
  // The term over body 0's faces and body 1's, as the servo builds it.
  std::shared_ptr<BodyContactTerm> Term() const {
    std::vector<ContactFace> plate_faces = {MakeContactFace(0, plate, &patch, &holed),
                                            MakeContactFace(1, plate, &patch, nullptr)};
    std::vector<ContactFace> ball_faces = {MakeContactFace(5, ball, &sphere, nullptr)};
    return plate == 0 ? MakeBodyContact(plate_faces, ball_faces)
                      : MakeBodyContact(ball_faces, plate_faces);
  }
  // q over (body 0, body 1): the ball's centre at `height` over the patch point uv, turned
  // sideways and tilted by `rng`, quaternions off the unit sphere.
  Eigen::VectorXd Over(const Eigen::Vector2d& uv, double height, std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const nurbs::SurfacePoint at = patch.Evaluate(uv[0], uv[1], 1);
    const Eigen::Vector3d normal = at.S_u.cross(at.S_v).normalized();
    const Eigen::Quaterniond qb =
        Eigen::Quaterniond(1, 0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng)).normalized() *
        Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
    Eigen::Matrix<double, 7, 1> qp, qs;
    qp << 0, 0, 0, 1.1, 0, 0, 0;
    qs << at.S + height * normal, 0.9 * qb.w(), 0.9 * qb.x(), 0.9 * qb.y(), 0.9 * qb.z();
    Eigen::VectorXd q(14);
    if (plate == 0) {
      q << qp, qs;
    } else {
      q << qs, qp;
    }
    return q;
  }
};

struct Row {
  double r = 0.0;
  Eigen::Matrix<double, 1, 7> J_a, J_b;  // the term's own body order
};
Row EvaluateAt(const Mechanism& m, const Term& t, TermState* st, const Eigen::VectorXd& q) {
  std::vector<BodyPose> poses;
  m.Poses(q, &poses);
  Eigen::VectorXd r(1);
  Eigen::MatrixXd Ja(1, 7), Jb(1, 7);
  t.Evaluate(poses, st, r, Ja, Jb);
  return {r[0], Ja, Jb};
}

// The face pair's own term, as a scene declaring it would build it (the trimmed face as f).
std::shared_ptr<const Term> FacePairTerm(const TwoBodies& s, int plate_face,
                                         const Eigen::Vector4d& u) {
  if (plate_face == 0) {
    return std::make_shared<TrimmedContactTerm>(s.plate, &s.patch, &s.holed, s.ball, &s.sphere, u);
  }
  return MakeSurfaceContact(s.plate, &s.patch, s.ball, &s.sphere, u);
}

class BodyContactTest : public ::testing::TestWithParam<bool> {};

TEST_P(BodyContactTest, OnAFacePairItIsThatPairsTermInItsBodyOrder) {
  const TwoBodies s(GetParam());
  const auto term = s.Term();
  EXPECT_EQ(term->body_a(), 0);
  EXPECT_EQ(term->body_b(), 1);
  const auto state = term->MakeState();
  auto& st = static_cast<BodyContactTerm::State&>(*state);
  // Free: far apart, no gradient.
  st.Deactivate();
  {
    Eigen::VectorXd q(14);
    q << 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 1, 0, 0, 0;
    const Row row = EvaluateAt(s.mech, *term, state.get(), q);
    EXPECT_EQ(row.r, ContactSlotState::kInactiveDistance);
    EXPECT_EQ(row.J_a.norm() + row.J_b.norm(), 0.0);
  }
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_j = 0.0, worst_h = 0.0;
  int edge_trials = 0;
  for (int trial = 0; trial < 12; ++trial) {
    // Over the hole near its rim (an edge contact on the holed face) or over the plate; the
    // untrimmed face has no hole.
    const int plate_face = trial % 3 == 2 ? 1 : 0;
    const bool over_hole = trial % 3 == 0;
    const double angle = 2 * M_PI * (trial + 0.3 * u(rng)) / 12;
    const double radius = over_hole ? 0.15 + 0.03 * u(rng) : 0.3 + 0.05 * u(rng);
    const Eigen::Vector2d uv =
        Eigen::Vector2d(0.5, 0.5) + radius * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const Eigen::VectorXd q = s.Over(uv, kRadius + 0.003 * u(rng), rng);
    std::vector<BodyPose> poses;
    s.mech.Poses(q, &poses);
    const Eigen::Vector4d seed =
        contact::ClosestSamplePair(s.patch, poses[static_cast<size_t>(s.plate)], s.sphere,
                                   poses[static_cast<size_t>(s.ball)], 31);
    // Moved to (ball, plate face) in either order, seeded in the order (f, g) = (plate, ball).
    ASSERT_TRUE(term->Target(&st, trial % 2 ? 5 : plate_face, trial % 2 ? plate_face : 5));
    EXPECT_EQ(term->faces()[static_cast<size_t>(st.f)].id, plate_face);
    EXPECT_EQ(st.swapped, s.plate == 1);
    EXPECT_EQ(st.trimmed, plate_face == 0);
    st.Activate(seed);
    const auto face_term = FacePairTerm(s, plate_face, seed);
    const auto face_state = face_term->MakeState();
    const Row mine = EvaluateAt(s.mech, *term, state.get(), q);
    const Row theirs = EvaluateAt(s.mech, *face_term, face_state.get(), q);
    EXPECT_EQ(mine.r, theirs.r) << trial;
    EXPECT_LT(std::abs(mine.r), 0.02);
    // Bit for bit, in this term's body order.
    const Eigen::Matrix<double, 1, 7>& plate_j = s.plate == 0 ? mine.J_a : mine.J_b;
    const Eigen::Matrix<double, 1, 7>& ball_j = s.plate == 0 ? mine.J_b : mine.J_a;
    EXPECT_EQ(plate_j, theirs.J_a) << trial;
    EXPECT_EQ(ball_j, theirs.J_b) << trial;
    EXPECT_EQ(st.extremum().u, static_cast<ContactSlotState&>(*face_state).extremum().u);
    if (plate_face == 0) {
      const bool on_edge = static_cast<TrimmedContactTerm::State&>(*st.cut_state).on_edge;
      EXPECT_EQ(on_edge, over_hole) << trial;
      edge_trials += on_edge;
    }
    // The Jacobian against central differences of re-solved values, the Hessian against central
    // differences of the analytic gradient.
    Eigen::Matrix<double, 1, 14> g;
    testing::TermValue(s.mech, *term, state.get(), q, &g);
    const Eigen::Matrix<double, 1, 14> fd =
        testing::ValueDifferences(s.mech, *term, state.get(), q, kH);
    for (int k = 0; k < 14; ++k) {
      worst_j = std::max(worst_j, std::abs(fd[k] - g[k]));
      EXPECT_NEAR(fd[k], g[k], 1e-7) << "trial " << trial << " q" << k;
    }
    const Eigen::Matrix<double, 14, 1> err =
        testing::HessianRowErrors(s.mech, *term, state.get(), q, 0.7, kH);
    for (int k = 0; k < 14; ++k) {
      worst_h = std::max(worst_h, err[k]);
      EXPECT_LT(err[k], 1e-5) << "trial " << trial << " Hessian row " << k;
    }
  }
  EXPECT_GE(edge_trials, 3);
  std::printf("plate body %d: largest |J - FD| %.2e, |H - FD(J)| (relative) %.2e; %d edge trials\n",
              s.plate, worst_j, worst_h, edge_trials);
}

TEST_P(BodyContactTest, MovingASlotAllocatesNothingAndRefusesPairsNotItsBodies) {
  const TwoBodies s(GetParam());
  const auto term = s.Term();
  const auto state = term->MakeState();
  auto& st = static_cast<BodyContactTerm::State&>(*state);
  EXPECT_FALSE(term->Target(&st, 0, 1));  // both on the plate
  EXPECT_FALSE(term->Target(&st, 0, 7));  // no face 7
  EXPECT_EQ(st.f, -1);
  ASSERT_GE(term->FaceIndex(5), 0);
  EXPECT_EQ(term->faces()[static_cast<size_t>(term->FaceIndex(5))].id, 5);
  EXPECT_EQ(term->FaceIndex(4), -1);
  std::mt19937_64 rng(5);
  const Eigen::VectorXd q = s.Over({0.5, 0.85}, kRadius + 0.001, rng);
  std::vector<BodyPose> poses;
  s.mech.Poses(q, &poses);
  Eigen::VectorXd r(1);
  Eigen::MatrixXd Ja(1, 7), Jb(1, 7);
  const long before = tangent::testing::AllocationCount();

  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(term->Target(&st, 5, k % 2));
    st.Activate(Eigen::Vector4d(0.5, 0.85, 0.5, 0.5));
    term->Evaluate(poses, state.get(), r, Ja, Jb);
    EXPECT_LT(std::abs(r[0] - 0.001), 1e-9) << k;
  }
  EXPECT_EQ(tangent::testing::AllocationCount() - before, 0);  // moves and evaluations
  EXPECT_EQ(tangent::testing::AllocationCount() - before, 0);
  // Faces on one body, a face twice, no faces: refused at construction.
  const ContactFace a = MakeContactFace(0, s.plate, &s.patch, nullptr);
  const ContactFace b = MakeContactFace(5, s.ball, &s.sphere, nullptr);
  EXPECT_THROW(BodyContactTerm({a}, {a}), std::invalid_argument);
  EXPECT_THROW(BodyContactTerm({a, a}, {b}), std::invalid_argument);
  EXPECT_THROW(BodyContactTerm({}, {b}), std::invalid_argument);
  EXPECT_THROW(BodyContactTerm({a}, {b, a}), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(BodyOrder, BodyContactTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "PlateFirst" : "BallFirst";
                         });

}  // namespace
}  // namespace tangent::optimizer
