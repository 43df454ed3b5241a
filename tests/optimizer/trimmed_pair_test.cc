// A contact between two trimmed faces (issue 34, seed 001's third trimming constraint): a domed
// plate with a round hole, and a second domed plate, upside down, of which only half is material
// (its edge a straight line of its domain, a curve on the dome in space). Slid across, the
// contact takes all four forms: the faces, the rim against the upper face, the upper edge
// against the plate, and the upper edge against the rim. Its value is continuous through every
// switch, edge against edge it equals the two edge curves' sampled distance, and its Jacobian
// and Hessian match central differences of re-measured values and of the analytic gradient.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "nurbs/trim.h"
#include "optimizer/trims.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kH = 1e-6;
using Form = contact::TrimmedForm;

struct PairScene {
  Mechanism mech;
  int lower_body, upper_body;
  // Both 0.2 m, 0.3 rad between the parameter directions, 4 mm domes, rational.
  nurbs::NurbsSurface lower = nurbs::MakeShearedPatch(0.3, 0.2, 0.004, true);
  nurbs::NurbsSurface upper = nurbs::MakeShearedPatch(0.3, 0.2, 0.002, true);
  // The materials end inside the surfaces' domains (as a CAD face's loops do), so that every
  // border of a material is a trim edge.
  nurbs::TrimmedDomain holed{
      {0, 0},
      {1, 1},
      nurbs::TrimLoop{{nurbs::MakePolyline2d(
          {{0.02, 0.02}, {0.98, 0.02}, {0.98, 0.98}, {0.02, 0.98}, {0.02, 0.02}})}},
      {nurbs::TrimLoop{{nurbs::MakeCircle2d({0.5, 0.5}, 0.2, true)}}}};
  nurbs::TrimmedDomain half{
      {0, 0},
      {1, 1},
      nurbs::TrimLoop{{nurbs::MakePolyline2d(
          {{0.05, 0.05}, {0.5, 0.05}, {0.5, 0.95}, {0.05, 0.95}, {0.05, 0.05}})}},
      {}};
  PairScene() {
    lower_body = mech.AddBody(Body{"lower"});
    upper_body = mech.AddBody(Body{"upper"});
  }
  std::shared_ptr<TrimmedContactTerm> Term(const Eigen::VectorXd& q) const {
    std::vector<BodyPose> poses;
    mech.Poses(q, &poses);
    return std::make_shared<TrimmedContactTerm>(
        lower_body, &lower, &holed, upper_body, &upper,
        contact::ClosestSamplePair(lower, poses[0], upper, poses[1], 31), ContactTracking{}, &half);
  }
};

// The upper plate turned over (about x) and by `yaw` about z, then tilted by `tilt` about its
// edge so that its material rises away from the edge; its domain's point (0.5, 0.5), on the
// edge, `height` over the lower plate's centre and `across` beside it, at right angles to the
// edge.
Eigen::VectorXd Place(const PairScene& s, double across, double height, double yaw, double tilt) {
  const Eigen::Quaterniond over(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  const nurbs::SurfacePoint mid = s.upper.Evaluate(0.5, 0.5, 1);
  const Eigen::Vector3d e = (over * mid.S_v).normalized();  // the edge runs along v
  Eigen::Vector3d m = -(over * mid.S_u);                    // towards the material (u < 0.5)
  m = (m - e * e.dot(m)).normalized();
  const double up = e.cross(m).z() > 0.0 ? 1.0 : -1.0;
  const Eigen::Quaterniond turn = Eigen::AngleAxisd(up * tilt, e) * over;
  const Eigen::Vector3d side = e.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d centre = s.lower.Evaluate(0.5, 0.5, 0).S;
  const Eigen::Vector3d p = centre + Eigen::Vector3d(0, 0, height) + across * side - turn * mid.S;
  Eigen::VectorXd q(14);
  q << 0, 0, 0, 1, 0, 0, 0, p, turn.w(), turn.x(), turn.y(), turn.z();
  return q;
}

constexpr auto* Value = &testing::TermValue;

const TrimmedContactTerm::State& StateOf(const TermState* st) {
  return static_cast<const TrimmedContactTerm::State&>(*st);
}

// The closest pair of points of two curves on two bodies within `window` of the parameters
// `around`, by sampling (4000 each, then 200 × 200 round the best): their distance, to ~1e-8 m.
double SampledDistance(const contact::BodyCurve& a, const BodyPose& pa, const contact::BodyCurve& b,
                       const BodyPose& pb, const Eigen::Vector2d& around, double window) {
  auto at = [](const contact::BodyCurve& c, const BodyPose& p, double t) {
    int span = 0;
    nurbs::SpanHint hint;
    return p.Point(c.Evaluate(t, &span, &hint).C);
  };
  auto best_in = [&](double s0, double s1, double t0, double t1, int n, Eigen::Vector2d* x) {
    std::vector<Eigen::Vector3d> pts(static_cast<size_t>(n + 1));
    for (int j = 0; j <= n; ++j) pts[static_cast<size_t>(j)] = at(b, pb, t0 + (t1 - t0) * j / n);
    double best = 1e300;
    for (int i = 0; i <= n; ++i) {
      const double si = s0 + (s1 - s0) * i / n;
      const Eigen::Vector3d p = at(a, pa, si);
      for (int j = 0; j <= n; ++j) {
        const double d = (p - pts[static_cast<size_t>(j)]).squaredNorm();
        if (d < best) best = d, *x = {si, t0 + (t1 - t0) * j / n};
      }
    }
    return std::sqrt(best);
  };
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  const double a0 = std::max(a.domain_begin(), around[0] - window),
               a1 = std::min(a.domain_end(), around[0] + window),
               b0 = std::max(b.domain_begin(), around[1] - window),
               b1 = std::min(b.domain_end(), around[1] + window);
  best_in(a0, a1, b0, b1, 4000, &x);
  const double wa = 2 * (a1 - a0) / 4000, wb = 2 * (b1 - b0) / 4000;
  return best_in(std::max(a0, x[0] - wa), std::min(a1, x[0] + wa), std::max(b0, x[1] - wb),
                 std::min(b1, x[1] + wb), 200, &x);
}

// The upper plate slid across the hole and back, its edge 2 mm over the lower plate's top.
struct Sweep {
  double from = -0.07, to = 0.07, height = 0.002, yaw = 0.4, tilt = 0.3;
  Eigen::VectorXd At(const PairScene& s, double t) const {
    return Place(s, (1 - t) * from + t * to, height, yaw, tilt);
  }
};

TEST(TrimmedPairTest, SlidAcrossTheContactTakesEveryFormContinuously) {
  // The upper plate slid in 2e-5 m steps across the hole and back. β is the distance between
  // the two materials' nearest points near the contact: every switch of form must keep it
  // 1-Lipschitz in the translation, and it may never rise faster than that. It may fall faster
  // where the local minimum followed meets another and both end (a fold: the straight edge's
  // crossings of the rim merging); the contact then takes the next one, lower.
  const PairScene s;
  const Sweep sweep;
  const Eigen::VectorXd q0 = sweep.At(s, 0.0), q1 = sweep.At(s, 1.0);
  const auto term = s.Term(q0);
  const auto state = term->MakeState();
  const double length = (q1.segment<3>(7) - q0.segment<3>(7)).norm();
  const int n = static_cast<int>(length / 2e-5);
  const double step = length / n;
  std::array<int, 4> visits{};
  double prev = Value(s.mech, *term, state.get(), q0, nullptr);
  Form form = StateOf(state.get()).measure.form;
  double worst_switch = 0.0, worst_rise = 0.0;
  int switches = 0, folds = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 1; k <= n; ++k) {
      const double t = pass == 0 ? static_cast<double>(k) / n : 1.0 - static_cast<double>(k) / n;
      const double beta = Value(s.mech, *term, state.get(), sweep.At(s, t), nullptr);
      const contact::TrimmedMeasure& m = StateOf(state.get()).measure;
      // Converged, or held at a joint of a loop (a corner of the upper plate's material).
      ASSERT_TRUE(m.status == contact::ExtremalStatus::kConverged) << "t " << t;
      if (m.form != form) {
        ++switches;
        worst_switch = std::max(worst_switch, std::abs(beta - prev) / step);
      } else if (prev - beta > 1.5 * step) {
        ++folds;
      }
      worst_rise = std::max(worst_rise, (beta - prev) / step);
      ++visits[static_cast<size_t>(m.form)];
      form = m.form;
      prev = beta;
    }
  }
  std::printf(
      "%d steps each way: face %d, rim on the upper face %d, upper edge on the plate %d, edge "
      "against edge %d; %d switches, largest |dbeta| / step at a switch %.4f; largest rise / step "
      "%.4f; %d folds\n",
      n, visits[0], visits[1], visits[2], visits[3], switches, worst_switch, worst_rise, folds);
  for (const Form f : {Form::kEdgeOfF, Form::kEdgeOfG, Form::kEdgeEdge}) {
    EXPECT_GT(visits[static_cast<size_t>(f)], 100) << static_cast<int>(f);
  }
  EXPECT_GE(switches, 4);
  EXPECT_EQ(switches, StateOf(state.get()).switches);
  EXPECT_LE(worst_switch, 1.0 + 1e-6);
  EXPECT_LE(worst_rise, 1.0 + 1e-6);
  EXPECT_LE(folds, 2);  // one where the edge leaves the hole's rim, each way
}

TEST(TrimmedPairTest, EveryEdgeFormIsExactWithExactDerivatives) {
  // Along the sweep, at poses away from a switch (the same form 0.004 of the sweep either side,
  // so that ±h stays in it): the Jacobian against central differences of re-measured β and the
  // Hessian against differences of the analytic gradient, in each edge form; edge against edge,
  // β against the two edges' sampled distance.
  const PairScene s;
  const Sweep sweep;
  const contact::TrimEdges rim(&s.lower, &s.holed), edge(&s.upper, &s.half);
  std::array<int, 4> checked{};
  std::array<double, 4> worst_j{}, worst_h{};
  double worst_value = 0.0;
  auto form_at = [&](const Eigen::VectorXd& q0, double t) {
    const auto probe = s.Term(q0);
    const auto st = probe->MakeState();
    for (int j = 0; j <= 20; ++j) Value(s.mech, *probe, st.get(), sweep.At(s, t * j / 20), nullptr);
    return StateOf(st.get()).measure.form;
  };
  for (int k = 0; k <= 40; ++k) {
    const double t = k / 40.0;
    Eigen::VectorXd q = sweep.At(s, t);
    const auto term = s.Term(sweep.At(s, 0.0));
    const auto state = term->MakeState();
    // Followed there along the sweep (as the servo does), then measured off the unit sphere.
    for (int j = 0; j <= 20; ++j)
      Value(s.mech, *term, state.get(), sweep.At(s, t * j / 20), nullptr);
    const Form form = StateOf(state.get()).measure.form;
    if (form == Form::kFace || form_at(sweep.At(s, 0.0), t - 0.004) != form ||
        form_at(sweep.At(s, 0.0), t + 0.004) != form) {
      continue;
    }
    q.segment<4>(3) *= 1.1;
    q.segment<4>(10) *= 0.9;
    Eigen::Matrix<double, 1, 14> g;
    const double beta = Value(s.mech, *term, state.get(), q, &g);
    const contact::TrimmedMeasure& m = StateOf(state.get()).measure;
    ASSERT_EQ(m.form, form) << "t " << t;
    // Held at a corner of a material (a joint of its loop) the row has the solver's
    // Gauss–Newton model, not an exact Hessian: not checked here.
    const bool at_joint =
        form == Form::kEdgeEdge
            ? !m.edge_edge.common_normal
            : (m.edge.ext.at_bound[0] || m.edge.ext.at_bound[1] || m.edge.ext.at_bound[2]);
    if (at_joint) continue;
    const size_t f = static_cast<size_t>(form);
    ++checked[f];
    if (form == Form::kEdgeEdge) {
      std::vector<BodyPose> poses;
      s.mech.Poses(q, &poses);
      const contact::EdgeEdgeFollow& ee = m.edge_edge;
      const double sampled = SampledDistance(rim.Curve(ee.loop_f, ee.piece_f), poses[0],
                                             edge.Curve(ee.loop_g, ee.piece_g), poses[1],
                                             ee.x + Eigen::Vector2d(0.0131, -0.0077), 0.06);
      EXPECT_GT(beta, 0.0) << "t " << t;  // apart here
      EXPECT_NEAR(beta, sampled, 1e-8) << "t " << t;
      worst_value = std::max(worst_value, std::abs(beta - sampled));
    }
    const Eigen::Matrix<double, 1, 14> fd =
        testing::ValueDifferences(s.mech, *term, state.get(), q, kH);
    for (int i = 0; i < 14; ++i) {
      EXPECT_NEAR(fd[i], g[i], 1e-7) << "form " << f << " t " << t << " q" << i;
      worst_j[f] = std::max(worst_j[f], std::abs(fd[i] - g[i]));
    }
    const Eigen::Matrix<double, 14, 1> err =
        testing::HessianRowErrors(s.mech, *term, state.get(), q, 0.7, kH);
    for (int i = 0; i < 14; ++i) {
      EXPECT_LT(err[i], 1e-6) << "form " << f << " t " << t << " Hessian row " << i;
      worst_h[f] = std::max(worst_h[f], err[i]);
    }
  }
  const char* names[] = {"face", "rim on the upper face", "upper edge on the plate",
                         "edge against edge"};
  for (size_t f = 1; f < 4; ++f) {
    std::printf("%s at %d poses: largest |J - FD| %.1e, largest |H - FD(J)| (relative) %.1e\n",
                names[f], checked[f], worst_j[f], worst_h[f]);
  }
  std::printf("edge against edge: |beta - sampled| %.1e m\n", worst_value);
  EXPECT_GE(checked[static_cast<size_t>(Form::kEdgeEdge)], 5);
  EXPECT_GE(checked[static_cast<size_t>(Form::kEdgeOfG)], 3);
}

}  // namespace
}  // namespace tangent::optimizer
