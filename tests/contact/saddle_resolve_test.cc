// Re-solves at a penetration extremum (issue 38). An interpenetrating pair's contact is the
// extremum of ½|d|² between the two facing normals, a saddle (or a maximum): ½|d|² decreases from
// it towards the intersection curve, where it is zero. The servo re-solves such a contact every
// tick from the last tick's parameters after a pose step of a few micrometres; the re-solve must
// stay on the same branch (the saddle moved, not a point of the intersection curve or a
// boundary), converge, and its closed-form Jacobian must agree with finite differences of those
// re-solves. Cases: a sphere in a plane, crossed cylinders (also near an end), linked tori
// pulled tight (the paperclip hook), touching and pressed, and a sphere pressed into random
// rational and non-rational sheets of degree 1–7, each turned at random. Where the branch
// itself ends along a step (a fold: next to a pitchfork the saddle meets the minima beside it
// and vanishes) there is nothing to stay on; such steps are counted apart.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "contact/contact_jacobian.h"
#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "testing/random_nurbs.h"

namespace tangent::contact {
namespace {

using nurbs::NurbsSurface;

Vector7d Coordinates(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Vector7d c;
  c << p, q.w(), q.x(), q.y(), q.z();
  return c;
}

Eigen::Quaterniond RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

// An interpenetrating pair and a seed from which its penetration extremum is found.
struct Case {
  std::string name;
  NurbsSurface f, g;
  Vector7d qf, qg;
  Eigen::Vector4d seed;
  double radius;  // the smallest curvature radius of the parts near the contact (m)
  std::vector<Eigen::Vector4d> more_seeds = {};  // tried in turn when `seed` ends elsewhere
  bool near_fold = false;  // next to a singular point of the branch (u(q) curves sharply)
};

// A rigid motion x applied to body coordinates q.
Vector7d Moved(const Eigen::Isometry3d& x, const Vector7d& q) {
  const Eigen::Quaterniond r(q[3], q[4], q[5], q[6]);
  return Coordinates(x * Eigen::Vector3d(q.head<3>()), Eigen::Quaterniond(x.linear()) * r);
}

// A random sheet of degree p (4 x 4 units about the origin, gently curved) for a sphere of
// radius 1 to be pressed into from above at its middle.
NurbsSurface Sheet(std::mt19937_64& rng, int p, bool rational) {
  std::uniform_real_distribution<double> coord(-1.0, 1.0), weight(0.6, 1.6);
  const int n = p + 2;
  std::vector<double> k(static_cast<size_t>(p + 1), 0.0);
  for (int i = 1; i < n - p; ++i) k.push_back(static_cast<double>(i) / (n - p));
  k.insert(k.end(), static_cast<size_t>(p + 1), 1.0);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      pts.emplace_back(-2.0 + 4.0 * i / (n - 1) + 0.1 * coord(rng),
                       -2.0 + 4.0 * j / (n - 1) + 0.1 * coord(rng), 0.15 * coord(rng));
      if (rational) w.push_back(weight(rng));
    }
  }
  return NurbsSurface(nurbs::KnotVector(p, k), nurbs::KnotVector(p, k), pts, w);
}

std::vector<Case> Cases() {
  std::vector<Case> out;
  std::mt19937_64 rng(3838);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond id = Eigen::Quaterniond::Identity();
  // The sphere's lowest point (turned a quarter about x: longitude 0.75, latitude 0.5).
  out.push_back({"sphere in a plane", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
                 nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0}),
                 Coordinates({0.01, -0.02, 0.03}, turn), Coordinates({0, 0, 0}, id),
                 Eigen::Vector4d(0.74, 0.51, 0.53, 0.44), 0.05});
  // Two cylinders of radius 1 cm crossing at right angles, axes 1.5 cm apart.
  const Eigen::Quaterniond to_x(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond to_y(Eigen::AngleAxisd(-std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  {
    const NurbsSurface cyl = nurbs::MakeCylinder(0.01, 0.2);
    const Vector7d qf = Coordinates({-0.1, 0, 0}, to_x), qg = Coordinates({0, -0.1, 0.015}, to_y);
    const Eigen::Vector4d seed =
        ClosestSamplePair(cyl, BodyPose::FromCoordinates(Coordinates({-0.1, 0, 0}, to_x)), cyl,
                          BodyPose::FromCoordinates(Coordinates({0, -0.1, 0.03}, to_y)), 24);
    out.push_back({"crossed cylinders", cyl, cyl, qf, qg, seed, 0.01});
    // The same crossing near the end of g (its edge 0.5 mm and 2 mm past f's axis; the
    // intersection curves run over the edge).
    for (double past : {0.5e-3, 2e-3}) {
      const Vector7d qg_end = Coordinates({0, -0.2 + past, 0.015}, to_y);
      out.push_back({"crossed cylinders, " + std::to_string(past * 1e3) + " mm from an end", cyl,
                     cyl, qf, qg_end, Eigen::Vector4d(seed[0], seed[1], seed[2], 1.0 - past / 0.2),
                     0.01});
    }
  }
  // Linked tori whose wires are thicker than the holes they pass through (the paperclip hook
  // pulled tight): the contact at the inner equators is a saddle of the signed distance even
  // apart; pressed together by delta it interpenetrates. Turned about the normal by `turn`.
  constexpr double mm = 1e-3;
  for (double about : {0.0, 0.35}) {
    for (double delta : {0.0, 1e-6, 2e-5, 1e-4}) {
      const double R1 = about == 0.0 ? 1.0 * mm : 1.2 * mm,
                   r1 = about == 0.0 ? 0.4 * mm : 0.45 * mm;
      const double R2 = about == 0.0 ? 2.0 * mm : 1.2 * mm,
                   r2 = about == 0.0 ? 0.8 * mm : 0.45 * mm;
      // Torus 1 turned about its axis and torus 2 raised by 0.1 r1, so that the contact lies on
      // no knot line of either (the rational circles are C1 in their parameter at the knots,
      // where central differences of re-solves are first order only).
      const double u1 = 1.0 - 0.3 / (2 * std::numbers::pi);
      out.push_back(
          {"linked tori, turn " + std::to_string(about) + ", pressed " + std::to_string(delta),
           nurbs::MakeTorus(R1, r1),
           nurbs::MakeTorus(R2, r2),
           Coordinates({0, 0, 0},
                       Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))),
           Coordinates({R1 - r1 + R2 - r2 + delta, 0, 0.1 * r1},
                       Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2 + about,
                                                            Eigen::Vector3d::UnitX()))),
           Eigen::Vector4d(u1, 0.5, 0.5, 0.5),
           r1,
           {{u1, 0.5, 0.5, 0.0},
            {u1, 0.5, 0.0, 0.5},
            {u1, 0.5, 0.0, 0.0},
            {u1, 0.5, 0.5, 0.25},
            {u1, 0.5, 0.5, 0.75},
            {u1, 0.45, 0.5, 0.5},
            {u1, 0.55, 0.5, 0.5},
            {u1, 0.45, 0.0, 0.5},
            {u1, 0.55, 0.0, 0.5}}});
    }
  }
  // The turned pair pressed 0.1 mm on the inner equators: next to the pitchfork where the
  // saddle meets the minima beside it, some steps end the branch (counted apart).
  out.push_back({"linked tori at a fold",
                 nurbs::MakeTorus(1.2 * mm, 0.45 * mm),
                 nurbs::MakeTorus(1.2 * mm, 0.45 * mm),
                 Coordinates({0, 0, 0}, id),
                 Coordinates({1.5 * mm + 1e-4, 0, 0},
                             Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2 + 0.35,
                                                                  Eigen::Vector3d::UnitX()))),
                 Eigen::Vector4d(0.0, 0.5, 0.5, 0.5),
                 0.45 * mm,
                 {{0.0, 0.5, 0.5, 0.0}, {0.0, 0.5, 0.0, 0.5}, {0.0, 0.5, 0.0, 0.0}},
                 true});
  for (int p = 1; p <= 7; ++p) {
    for (bool rational : {false, true}) {
      out.push_back(
          {"sphere in a degree " + std::to_string(p) + (rational ? " rational" : "") + " sheet",
           nurbs::MakeSphere(Eigen::Vector3d::Zero(), 1.0), Sheet(rng, p, rational),
           Coordinates({0.2, -0.1, 0.7}, turn), Coordinates({0, 0, 0}, id),
           Eigen::Vector4d(0.75, 0.5, 0.55, 0.475), 0.5});
    }
  }
  return out;
}

// The solve at coordinates qf, qg from a seed.
SurfaceSurfaceExtremum Solve(const Case& c, const Vector7d& qf, const Vector7d& qg,
                             const Eigen::Vector4d& seed, SurfacePairEval* e = nullptr) {
  return SolveSurfaceSurface(c.f, BodyPose::FromCoordinates(qf), c.g, BodyPose::FromCoordinates(qg),
                             seed, {}, e);
}

TEST(SaddleResolveTest, ReSolvesAfterSmallPoseStepsStayOnThePenetrationExtremum) {
  std::mt19937_64 rng(3839);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  int total = 0, on_branch = 0, cases = 0, at_fold = 0;
  double worst_branch = 0.0, worst_fd = 0.0;
  for (const Case& c : Cases()) {
    for (int pose = 0; pose < 4; ++pose) {
      Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
      if (pose > 0) {
        x.linear() = RandomRotation(rng).toRotationMatrix();
        x.translation() = Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
      }
      const Vector7d qf = Moved(x, c.qf), qg = Moved(x, c.qg);
      SurfacePairEval e0;
      SurfaceSurfaceExtremum at = Solve(c, qf, qg, c.seed, &e0);
      for (const Eigen::Vector4d& seed : c.more_seeds) {
        if (at.status == ExtremalStatus::kConverged && at.kind != ExtremumKind::kMinimum) break;
        at = Solve(c, qf, qg, seed, &e0);
      }
      const std::string where = c.name + ", pose " + std::to_string(pose);
      ASSERT_EQ(at.status, ExtremalStatus::kConverged) << where;
      ASSERT_NE(at.kind, ExtremumKind::kMinimum) << where;
      ++cases;
      Matrix4x14 u_q;
      ASSERT_TRUE(ContactJacobianClosedForm(e0, BodyPose::FromCoordinates(qf),
                                            BodyPose::FromCoordinates(qg), &u_q))
          << where;
      // Steps of both bodies' coordinates as a servo tick makes them, of length h (m, and unit
      // quaternion components): the re-solve from the last parameters is the extremum the
      // Jacobian predicts, to second order in h.
      for (double h : {1e-6, 2e-6, 5e-6, 1e-5, 2e-5}) {
        for (int dir = 0; dir < 6; ++dir) {
          Eigen::Matrix<double, 14, 1> dq;
          for (int i = 0; i < 14; ++i) dq[i] = uni(rng);
          dq *= h / dq.norm();
          const SurfaceSurfaceExtremum r = Solve(c, qf + dq.head<7>(), qg + dq.tail<7>(), at.u);
          // The branch: followed in 32 steps of h/32, each re-solved from the last.
          Eigen::Vector4d followed = at.u;
          int follow_fail = 0;
          double follow_rcond = 1.0;
          for (int k = 1; k <= 32; ++k) {
            const SurfaceSurfaceExtremum fk =
                Solve(c, qf + dq.head<7>() * (k / 32.0), qg + dq.tail<7>() * (k / 32.0), followed);
            followed = fk.u;
            follow_fail += fk.status != ExtremalStatus::kConverged;
            follow_rcond = std::min(follow_rcond, fk.rcond);
          }
          const double moved = ParameterDistance(c.f, c.g, followed, at.u);
          const double off = ParameterDistance(c.f, c.g, r.u, followed);
          // Where the followed branch itself meets a singular point (a fold: the saddle and a
          // neighbouring extremum meet and vanish, as past the pitchfork of crossing wires turned
          // towards parallel), there is no branch to stay on: counted, and the answer need only
          // be an honest one (finite, in the domain, its status saying whether it converged).
          if (follow_fail > 0) {
            ++at_fold;
            EXPECT_TRUE(r.u.allFinite() && std::isfinite(r.beta)) << where;
            continue;
          }
          const bool ok = r.status == ExtremalStatus::kConverged && off <= 1e-9;
          ++total;
          on_branch += ok;
          worst_branch = std::max(worst_branch, off);
          EXPECT_TRUE(ok) << where << ", step " << h << " dir " << dir << ": " << ToString(r.status)
                          << " after " << r.iterations << " iterations, beta " << r.beta << " (was "
                          << at.beta << "), " << off << " from the branch, which moved " << moved
                          << " (first order: " << (u_q * dq).cwiseAbs().maxCoeff() << "), rcond "
                          << r.rcond << "; follower: " << follow_fail << " unconverged, rcond "
                          << follow_rcond;
        }
      }
      // The closed-form Jacobian against central differences of re-solves, through the world
      // contact points and β it moves (f_q = ∂f/∂q + [f_u f_v] u_q, …): those are smooth in q,
      // while u itself is only C1 where a contact sits on a knot of a rational circle (the tori's
      // inner equators), and there central differences of u are first order. Step 1e-4 of the
      // parts' curvature radius: truncation ~1e-8 relative (1e-6 next to a fold, where u_q is
      // ~30 times larger and its own derivative larger still).
      Matrix3x14 f_q, g_q;
      Row14 beta_q;
      PointAndDistanceJacobians(e0, BodyPose::FromCoordinates(qf), BodyPose::FromCoordinates(qg),
                                u_q, &f_q, &g_q, &beta_q);
      const double fd_h = (c.near_fold ? 1e-6 : 1e-4) * c.radius;
      Eigen::Matrix<double, 7, 14> analytic, fd;
      analytic << f_q, g_q, beta_q;
      for (int i = 0; i < 14; ++i) {
        Eigen::Matrix<double, 7, 1> y[2];
        for (int side = 0; side < 2; ++side) {
          Vector7d a = qf, b = qg;
          (i < 7 ? a[i] : b[i - 7]) += side == 0 ? fd_h : -fd_h;
          const SurfaceSurfaceExtremum r = Solve(c, a, b, at.u);
          EXPECT_EQ(r.status, ExtremalStatus::kConverged) << where << ", coordinate " << i;
          y[side] << r.p_f, r.p_g, r.beta;
        }
        fd.col(i) = (y[0] - y[1]) / (2 * fd_h);
      }
      const double rel = (analytic - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff();
      worst_fd = std::max(worst_fd, rel);
      EXPECT_LE(rel, 1e-6) << where << ": closed-form Jacobian against finite differences";
    }
  }
  std::printf(
      "%d saddle and penetration extrema re-solved after coordinate steps of 1e-6..2e-5: %d of %d "
      "on the branch (worst %.1e from the branch followed in steps of h/32), %d more steps past a "
      "fold of the branch; closed-form Jacobian (points, β) against finite "
      "differences of re-solves: worst %.1e relative\n",
      cases, on_branch, total, worst_branch, at_fold, worst_fd);
}

}  // namespace
}  // namespace tangent::contact
