#pragma once

#include <vector>

// The spatial four-bar of seed 001 Fig. 7: ground, crank (revolute to ground about z), coupler
// ("top link", universal joint to the crank), rocker (spherical joint to the coupler, revolute to
// ground about y). One degree of freedom (RUSR). A point grasp pulls the middle of the coupler.

#include <numbers>

#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
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
    AddJoints(&p);
    *goal = MakePositionGoal(grasp, target);
    p.AddObjective(*goal, grasp_weight);
    return p;
  }

  void AddJoints(Problem* p) const {
    p->AddEquality(RevoluteJoint({ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}},
                                 {crank, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}));
    p->AddEquality(UniversalJoint({crank, {0, 0.1, 0}, {1, 0, 0}, {0, 1, 0}},
                                  {coupler, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}));
    p->AddEquality(SphericalJoint({coupler, {0.3, -0.1, 0.15}}, {rocker, {0, 0, 0.15}}));
    p->AddEquality(RevoluteJoint({ground, {0.3, 0, 0}, {0, 1, 0}, {1, 0, 0}},
                                 {rocker, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}}));
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

/// The same four-bar grasped through a floating surface–surface contact (seed 001 Fig. 7): a
/// fingertip (a sphere of 4 mm radius on its own body) held by the hand through position and
/// orientation goals, touching a free-form pad on the coupler: a 6 x 6 cm rational bicubic patch
/// with a 3 mm bump and parameter directions 35° from orthogonal, facing +x at the grasp point.
/// The contact is bilateral (β = 0): the tip may roll and slide on the pad but not leave it, so
/// the hand's motion along the pad's normal drives the coupler while tangential motion slides.
struct FloatingGraspFourBar : FourBar {
  int finger;
  /// Poles along ±y, away from the contact, which stays near the tip's −x side.
  nurbs::NurbsSurface tip = nurbs::Transformed(
      nurbs::MakeSphere({0, 0, 0}, 0.004),
      Eigen::Isometry3d(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX())));
  nurbs::NurbsSurface pad;

  static nurbs::NurbsSurface MakePad() {
    const nurbs::NurbsSurface flat = nurbs::MakeShearedPatch(0.6, 0.06, 0.003, true);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY())
                                  .toRotationMatrix();  // z → x
    const Eigen::Vector3d centre = flat.Evaluate(0.5, 0.5, 0).S;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = R;
    X.translation() = Eigen::Vector3d(0.15, -0.05, 0.075) - R * centre;
    return nurbs::Transformed(flat, X);
  }
  /// The tip's centre 4 mm off the pad's centre along its normal (world; the coupler starts
  /// unrotated).
  Eigen::Vector3d Reach() const {
    const nurbs::SurfacePoint c = pad.Evaluate(0.5, 0.5, 1);
    return 0.004 * c.S_u.cross(c.S_v).normalized();
  }

  FloatingGraspFourBar() : pad(MakePad()) {
    Body f{"finger"};
    f.mass = 0.02;
    f.inertia = Eigen::Matrix3d::Identity() * 1.3e-7;
    f.pose << Eigen::Vector3d(0.15, 0.05, 0.075) + Reach(), 1, 0, 0, 0;
    finger = mechanism.AddBody(f);
  }

  Eigen::Vector3d HandPoint(int step) const { return PathPoint(step) + Reach(); }

  /// A seed (u, v, s, t) for the tip–pad contact at the initial poses: the closest sample pair.
  Eigen::Vector4d RestSeed() const {
    std::vector<BodyPose> poses;
    mechanism.Poses(mechanism.InitialCoordinates(), &poses);
    return contact::ClosestSamplePair(tip, poses[static_cast<size_t>(finger)], pad,
                                      poses[static_cast<size_t>(coupler)], 47);
  }

  Problem MakeProblem(std::shared_ptr<PositionGoalTerm>* goal,
                      std::shared_ptr<SurfaceContactTerm>* contact, const Eigen::Vector4d& seed,
                      double grasp_weight = 1.0) const {
    Problem p(mechanism);
    AddJoints(&p);
    *contact = MakeSurfaceContact(finger, &tip, coupler, &pad, seed);
    p.AddEquality(*contact);
    *goal = MakePositionGoal({finger, {0, 0, 0}}, HandPoint(0));
    p.AddObjective(*goal, grasp_weight);
    // The hand holds the fingertip's orientation too (a 6-DOF grasp): without it a sphere's
    // spin is free up to its tiny inertia and the contact point wanders over the tip.
    p.AddObjective(OrientationGoal(finger, Eigen::Matrix3d::Identity(), {1, 1, 1}),
                   1e-2 * grasp_weight);
    return p;
  }
};

}  // namespace tangent::optimizer::testing
