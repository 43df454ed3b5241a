#pragma once

// The spatial four-bar of seed 001 Fig. 7: ground, crank (revolute to ground about z), coupler
// ("top link", universal joint to the crank), rocker (spherical joint to the coupler, revolute to
// ground about y). One degree of freedom (RUSR). A point grasp pulls the middle of the coupler.

#include <numbers>

#include "optimizer/goals.h"
#include "optimizer/joints.h"
#include "optimizer/problem.h"

namespace tangent::optimizer::testing {

struct FourBar {
  int ground, crank, coupler, rocker;
  Attachment grasp;  ///< middle of the coupler
  Mechanism mechanism;

  FourBar() {
    Body g{"ground"};
    g.fixed = true;
    ground = mechanism.AddBody(g);
    // Links as slender bars of 0.1–0.35 m, ~0.05–0.2 kg; body frames at their proximal joints,
    // initially aligned with the world.
    Body c{"crank"}, u{"coupler"}, r{"rocker"};
    c.pose << 0, 0, 0, 1, 0, 0, 0;
    c.mass = 0.05;
    c.inertia = Eigen::Vector3d(2e-4, 1e-5, 2e-4).asDiagonal();
    u.pose << 0, 0.1, 0, 1, 0, 0, 0;
    u.mass = 0.2;
    u.inertia = Eigen::Vector3d(2e-3, 2e-3, 2e-3).asDiagonal();
    r.pose << 0.3, 0, 0, 1, 0, 0, 0;
    r.mass = 0.08;
    r.inertia = Eigen::Vector3d(6e-4, 6e-4, 1e-5).asDiagonal();
    crank = mechanism.AddBody(c);
    coupler = mechanism.AddBody(u);
    rocker = mechanism.AddBody(r);
    grasp = Attachment{coupler, {0.15, -0.05, 0.075}};
  }

  /// Joints as equality constraints; the grasp as a weighted position goal at `target`, whose
  /// handle is returned in *goal so the target can move.
  Problem MakeProblem(const Eigen::Vector3d& target, std::shared_ptr<PositionGoalTerm>* goal,
                      double grasp_weight = 1.0) const {
    Problem p(mechanism);
    p.AddEquality(RevoluteJoint({ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}},
                                {crank, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}));
    p.AddEquality(UniversalJoint({crank, {0, 0.1, 0}, {1, 0, 0}, {0, 1, 0}},
                                 {coupler, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}));
    p.AddEquality(SphericalJoint({coupler, {0.3, -0.1, 0.15}}, {rocker, {0, 0, 0.15}}));
    p.AddEquality(RevoluteJoint({ground, {0.3, 0, 0}, {0, 1, 0}, {1, 0, 0}},
                                {rocker, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}}));
    *goal = MakePositionGoal(grasp, target);
    p.AddObjective(*goal, grasp_weight);
    return p;
  }

  /// The drag path: a circle of radius 1 cm through the coupler's initial midpoint, in the x–z
  /// plane, walked in steps of 1 mm (1000 steps: 16 turns). The grasp follows the point of its
  /// coupler curve nearest the hand; a radius below the coupler curve's radius of curvature keeps
  /// that point continuous. (Larger circles reach targets where the nearest point jumps to the
  /// other side of the crank's swing — a fold, where a drag must travel far: "solve for goal".)
  /// At the initial, symmetric configuration the one degree of freedom moves the midpoint along
  /// x, so the circle must not lie in a plane x = const.
  static Eigen::Vector3d PathPoint(int step) {
    const Eigen::Vector3d start(0.15, 0.05, 0.075);
    const double r = 0.01, s = 1e-3 * step / r;
    return start + r * Eigen::Vector3d(std::sin(s), 0, 1 - std::cos(s));
  }
};

}  // namespace tangent::optimizer::testing
