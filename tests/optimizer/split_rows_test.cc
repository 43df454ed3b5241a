// The rows of a split contact (docs/contact.md, "Rows that stay on their minimum"): two wire
// rings turned past their pitchfork, where the one extremal pair became a saddle with a minimum
// either side. A row with keep_off_saddles whose evaluation ends on the saddle, or uphill on the
// other minimum, goes back to its own; without it, it stays where Newton ended.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "contact/global.h"
#include "contact/global_minima.h"
#include "contact/relative_curvature.h"
#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "testing/term_derivatives.h"

namespace tangent::optimizer {
namespace {

constexpr double kMajor = 1.2e-3, kMinor = 0.45e-3;

// The hooks scene's rings (testing/conformal_scenes.h, kHooksScene): the fixed one about z at
// the origin, the other's surface turned 90° about x, its body at (1.5 mm, 0, 0) turned by
// `turn` about x (the pitchfork is at 14.5°).
struct Rings {
  Mechanism mech;
  int a, b;
  nurbs::NurbsSurface fixed = nurbs::MakeTorus(kMajor, kMinor);
  nurbs::NurbsSurface wire = nurbs::MakeTorus(kMajor, kMinor);
  Eigen::VectorXd q = Eigen::VectorXd(14);
  std::vector<BodyPose> poses;
  explicit Rings(double turn_deg, double x = 1.5e-3) {
    a = mech.AddBody(Body{"fixed_ring"});
    b = mech.AddBody(Body{"ring"});
    const Eigen::Quaterniond r =
        Eigen::Quaterniond(
            Eigen::AngleAxisd(turn_deg * std::numbers::pi / 180, Eigen::Vector3d::UnitX())) *
        Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
    q << 0, 0, 0, 1, 0, 0, 0, x, 0, 0, r.w(), r.x(), r.y(), r.z();
    mech.Poses(q, &poses);
  }
};

// The saddle between the rings at s's poses and the minimum either side of it (side 0, 1).
struct Split {
  contact::SurfaceSurfaceExtremum saddle;
  Eigen::Vector4d minimum[2];
  double beta = 0.0;  ///< the minima's (equal by symmetry)
};
Split SplitAt(const Rings& s) {
  const BodyPose& pa = s.poses[static_cast<size_t>(s.a)];
  const BodyPose& pb = s.poses[static_cast<size_t>(s.b)];
  contact::SurfacePairEval at;
  Split out;
  out.saddle = contact::SolveSurfaceSurface(
      s.fixed, pa, s.wire, pb, Eigen::Vector4d(0, 0.5, 0.5, 0.5), contact::kContinuation, &at);
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(at);
  EXPECT_TRUE(rc.crossing);
  std::vector<contact::GlobalContact> minima;
  contact::internal::MinimaBeside(s.fixed, pa, s.wire, pb, out.saddle, at, rc, {}, 0, 1, &minima);
  EXPECT_EQ(minima.size(), 2u);
  for (size_t k = 0; k < 2 && k < minima.size(); ++k) out.minimum[k] = minima[k].u;
  if (!minima.empty()) out.beta = minima[0].beta;
  return out;
}

// The start a fraction t of the way from the saddle to a minimum (the periodic u the short way).
Eigen::Vector4d Toward(const Eigen::Vector4d& saddle, const Eigen::Vector4d& minimum, double t) {
  Eigen::Vector4d d = minimum - saddle;
  for (int i = 0; i < 4; ++i) d[i] -= std::round(d[i]);  // (the tori's domains are [0, 1])
  Eigen::Vector4d u = saddle + t * d;
  for (int i = 0; i < 4; ++i) u[i] -= std::floor(u[i]);
  return u;
}

// Just past the pitchfork the minima lie 0.01–0.02 of the domain either side of the saddle,
// and Newton from anywhere in the inner half between the saddle and one of them ends on the
// saddle or on the other minimum. A row that keeps off saddles ends on the minimum on its own
// side from every start, and counts a walk exactly where Newton alone ended elsewhere.
TEST(SplitRowsTest, ARowOfASplitPairEndsOnItsOwnMinimumWhereNewtonEndsElsewhere) {
  int newton_elsewhere = 0, starts = 0;
  for (const double turn : {14.6, 14.8, 15.2}) {
    const Rings s(turn);
    const Split split = SplitAt(s);
    for (int side = 0; side < 2; ++side) {
      for (const double t : {0.05, 0.2, 0.35, 0.5, 0.7, 0.9, 1.3}) {
        const Eigen::Vector4d start = Toward(split.saddle.u, split.minimum[side], t);
        bool elsewhere = false;
        for (const bool keep : {false, true}) {
          const auto term = MakeSurfaceContact(s.a, &s.fixed, s.b, &s.wire, start);
          const std::unique_ptr<TermState> st_ptr = term->MakeState();
          auto& st = static_cast<SurfaceContactTerm::State&>(*st_ptr);
          st.keep_off_saddles = keep;
          testing::TermValue(s.mech, *term, &st, s.q, nullptr);
          const double off =
              contact::ParameterDistance(s.fixed, s.wire, st.ext.u, split.minimum[side]);
          if (!keep) {
            elsewhere = off > 1e-6;
            newton_elsewhere += elsewhere;
            continue;
          }
          ++starts;
          EXPECT_LT(off, 1e-8) << turn << " deg, side " << side << ", t " << t;
          EXPECT_NEAR(st.ext.beta, split.beta, 1e-15) << turn << " deg, side " << side;
          EXPECT_EQ(st.walks, elsewhere ? 1 : 0) << turn << " deg, side " << side << ", t " << t;
        }
      }
    }
  }
  std::printf("split rows: %d starts, Newton alone ends elsewhere from %d\n", starts,
              newton_elsewhere);
  EXPECT_EQ(starts, 42);
  // (What the rows correct: without keep_off_saddles, these starts end elsewhere.)
  EXPECT_GE(newton_elsewhere, 20);  // (24 measured)
}

// A row's held or undecided evaluations can carry its parameters across the saddle with the
// tracker; the side it keeps to is where it last ended on a minimum (own_u), not where it was
// last held.
TEST(SplitRowsTest, ARowCarriedAcrossTheSaddleGoesBackToTheSideItLastHeld) {
  const Rings s(14.8);
  const Split split = SplitAt(s);
  for (int side = 0; side < 2; ++side) {
    for (const double t : {0.05, 0.2, 0.35, 0.6, 1.0}) {
      const auto term = MakeSurfaceContact(s.a, &s.fixed, s.b, &s.wire, split.minimum[side]);
      const std::unique_ptr<TermState> st_ptr = term->MakeState();
      auto& st = static_cast<SurfaceContactTerm::State&>(*st_ptr);
      st.keep_off_saddles = true;
      st.u = Toward(split.saddle.u, split.minimum[1 - side], t);  // carried across
      testing::TermValue(s.mech, *term, &st, s.q, nullptr);
      EXPECT_LT(contact::ParameterDistance(s.fixed, s.wire, st.ext.u, split.minimum[side]), 1e-8)
          << "side " << side << ", t " << t;
      EXPECT_EQ(st.walks, 1) << "side " << side << ", t " << t;
    }
  }
}

// β's gradient at a row walked back to its minimum, against central differences of β over both
// bodies' coordinates (each from a fresh row of the split pair seeded at that minimum).
TEST(SplitRowsTest, AWalkedRowsGradientMatchesFiniteDifferences) {
  const Rings s(14.8);
  const Split split = SplitAt(s);
  const auto term = MakeSurfaceContact(s.a, &s.fixed, s.b, &s.wire,
                                       Toward(split.saddle.u, split.minimum[0], 0.2));
  const std::unique_ptr<TermState> st_ptr = term->MakeState();
  auto& st = static_cast<SurfaceContactTerm::State&>(*st_ptr);
  st.keep_off_saddles = true;
  Eigen::Matrix<double, 1, 14> grad;
  testing::TermValue(s.mech, *term, &st, s.q, &grad);
  ASSERT_EQ(st.walks, 1);
  constexpr double h = 1e-9;  // (β''' is large by a pitchfork: ~1e10 in metres)
  for (int i = 0; i < 14; ++i) {
    double beta[2];
    for (int k = 0; k < 2; ++k) {
      Eigen::VectorXd q = s.q;
      q[i] += k == 0 ? h : -h;
      const auto fresh = MakeSurfaceContact(s.a, &s.fixed, s.b, &s.wire, st.ext.u);
      const std::unique_ptr<TermState> f = fresh->MakeState();
      static_cast<SurfaceContactTerm::State&>(*f).keep_off_saddles = true;
      beta[k] = testing::TermValue(s.mech, *fresh, f.get(), q, nullptr);
    }
    const double fd = (beta[0] - beta[1]) / (2 * h);
    EXPECT_NEAR(grad[i], fd, 1e-6 * std::max(1.0, std::abs(fd))) << "coordinate " << i;
  }
}

}  // namespace
}  // namespace tangent::optimizer
