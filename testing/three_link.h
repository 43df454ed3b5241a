#pragma once

// A three-link arm for design tests and benchmarks: links of 0.3, 0.25 and 0.2 m, revolute about
// z, y, y (a planar elbow on a turntable), the tip at the end of the last link.

#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "optimizer/joints.h"
#include "optimizer/mechanism.h"
#include "optimizer/problem.h"

namespace tangent::optimizer::testing {

// Three links of 0.3, 0.25 and 0.2 m: revolute about z, y, y (a planar elbow on a turntable).
struct ThreeLink {
  Mechanism mech;
  int ground, l1, l2, l3;
  std::vector<std::pair<Attachment, Attachment>> joints;
  Attachment tip;
  ThreeLink() {
    Body g{"ground"};
    g.fixed = true;
    ground = mech.AddBody(g);
    Body a{"l1"}, b{"l2"}, c{"l3"};
    a.pose << 0, 0, 0, 1, 0, 0, 0;
    b.pose << 0, 0, 0.3, 1, 0, 0, 0;
    c.pose << 0, 0, 0.55, 1, 0, 0, 0;
    l1 = mech.AddBody(a);
    l2 = mech.AddBody(b);
    l3 = mech.AddBody(c);
    joints = {{{ground, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}, {l1, {0, 0, 0}, {0, 0, 1}, {1, 0, 0}}},
              {{l1, {0, 0, 0.3}, {0, 1, 0}, {0, 0, 1}}, {l2, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
              {{l2, {0, 0, 0.25}, {0, 1, 0}, {0, 0, 1}}, {l3, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}}}};
    tip = Attachment{l3, {0, 0, 0.2}};
  }
  Problem MakeProblem() const {
    Problem p(mech);
    for (const auto& [a, b] : joints) p.AddEquality(RevoluteJoint(a, b));
    return p;
  }
};

// The arm bent by joint angles (default: turntable 0.3 rad, elbow 0.7 rad, wrist −0.4 rad, a
// regular configuration), placed link by link.
inline Eigen::VectorXd Bent(const ThreeLink& arm,
                            const Eigen::Vector3d& angle = Eigen::Vector3d(0.3, 0.7, -0.4)) {
  Eigen::VectorXd q = arm.mech.InitialCoordinates();
  const Eigen::Quaterniond r1(Eigen::AngleAxisd(angle[0], Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond r2 =
      r1 * Eigen::Quaterniond(Eigen::AngleAxisd(angle[1], Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond r3 =
      r2 * Eigen::Quaterniond(Eigen::AngleAxisd(angle[2], Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d p2 = r1 * Eigen::Vector3d(0, 0, 0.3);
  const Eigen::Vector3d p3 = p2 + r2 * Eigen::Vector3d(0, 0, 0.25);
  q.segment<7>(0) << 0, 0, 0, r1.w(), r1.x(), r1.y(), r1.z();
  q.segment<7>(7) << p2, r2.w(), r2.x(), r2.y(), r2.z();
  q.segment<7>(14) << p3, r3.w(), r3.x(), r3.y(), r3.z();
  return q;
}

}  // namespace tangent::optimizer::testing
