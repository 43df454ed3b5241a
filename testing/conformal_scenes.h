#pragma once

// Issue 33's canonical conformal contacts as scenes (tests/server/conformal_test.cc, the
// stability suite): pairs whose surfaces nearly coincide over a line or a patch.

#include <numbers>

#include <Eigen/Geometry>

#include "testing/torus_gap.h"

namespace tangent::testing {

// The groove: a cylinder of radius 5.05 mm facing its axis, 40 mm along x; the rod: radius
// 5 mm, 20 mm long, lying on the groove's bottom line (0.05 mm below the groove's axis).
//
// In both scenes the surfaces' offsets overlap far from the contact: about √(4 r R) round it
// (r the offset, 0.27 mm; R the relative curvature radius, 1/(1/5 − 1/5.05) = 505 mm), 23 mm,
// the whole part. Spheres of neglect of 6 mm (their far reach 24 mm) keep the global stage from
// testing every block of both parts round a tracked contact (docs/trimming.md, "Peg in hole").
inline constexpr const char* kGrooveScene = R"JSON({
  "name": "rod in a groove",
  "length_unit": "mm",
  "bodies": [
    {"name": "block", "fixed": true},
    {"name": "rod", "position": [0, 0, -0.05], "mass": 0.01, "inertia": [8e-07, 8e-07, 1e-07]}
  ],
  "surfaces": [
    {"name": "groove", "body": "block", "type": "cylinder", "radius": 5.05, "height": 40,
     "position": [-20, 0, 0], "quaternion": [0.7071067811865476, 0, 0.7071067811865476, 0],
     "reverse_normal": true},
    {"name": "rod_side", "body": "rod", "type": "cylinder", "radius": 5, "height": 20,
     "position": [-10, 0, 0], "quaternion": [0.7071067811865476, 0, 0.7071067811865476, 0]}
  ],
  "contacts": [{"a": "groove", "b": "rod_side", "kind": "unilateral", "max_contacts": 2}],
  "grasp": {"body": "rod", "point": [0, 0, 0], "hold_orientation": 0.01},
  "device": {"id": 1, "scale": 1.0, "stiffness": 300, "damping": 1.0, "max_force": 3.3,
             "max_force_rate": 500, "ramp_time": 1.0},
  "offset": {"tolerance": 0.02, "margin": 0.25},
  "global_stage": {"neglect_radius": 6}
})JSON";

// A ball of radius 5 mm in a spherical socket of 5.05 mm, resting at its bottom: a patch contact
// (the relative curvature 1/5 − 1/5.05 per mm is small in every direction but not zero, so one
// extremal point holds it). Both spheres have their poles at the bottom, where they touch: the
// contact starts on two poles, and the ball's point crosses its pole when it turns
// (docs/contact.md, "Pole charts").
inline constexpr const char* kSocketScene = R"JSON({
  "name": "ball in a socket",
  "length_unit": "mm",
  "bodies": [
    {"name": "block", "fixed": true},
    {"name": "ball", "position": [0, 0, -0.05], "mass": 0.01, "inertia": [1e-07, 1e-07, 1e-07]}
  ],
  "surfaces": [
    {"name": "socket", "body": "block", "type": "sphere", "radius": 5.05, "reverse_normal": true},
    {"name": "ball_surface", "body": "ball", "type": "sphere", "radius": 5}
  ],
  "contacts": [{"a": "socket", "b": "ball_surface", "kind": "unilateral", "max_contacts": 2}],
  "grasp": {"body": "ball", "point": [0, 0, 0], "hold_orientation": 0.01},
  "device": {"id": 1, "scale": 1.0, "stiffness": 300, "damping": 1.0, "max_force": 3.3,
             "max_force_rate": 500, "ramp_time": 1.0},
  "offset": {"tolerance": 0.02, "margin": 0.25},
  "global_stage": {"neglect_radius": 6}
})JSON";

// A box of 20 x 20 x 10 mm resting on its bottom face 0.05 mm over a 60 mm square floor: a face
// contact (both faces flat, their extremal pair a continuum). Only the bottom face and the floor
// are a declared pair: the box's other faces lie above its bottom corners for any tilt under a
// right angle. The grasp is at the box's centre.
inline constexpr const char* kBoxScene = R"JSON({
  "name": "box on a floor",
  "length_unit": "mm",
  "bodies": [
    {"name": "ground", "fixed": true},
    {"name": "box", "position": [0, 0, 0.05], "mass": 0.01, "inertia": [4e-07, 4e-07, 7e-07]}
  ],
  "surfaces": [
    {"name": "floor", "body": "ground", "type": "plane_patch", "origin": [-30, -30, 0],
     "edge_u": [60, 0, 0], "edge_v": [0, 60, 0]},
    {"name": "bottom", "body": "box", "type": "plane_patch", "origin": [-10, -10, 0],
     "edge_u": [0, 20, 0], "edge_v": [20, 0, 0]},
    {"name": "top", "body": "box", "type": "plane_patch", "origin": [-10, -10, 10],
     "edge_u": [20, 0, 0], "edge_v": [0, 20, 0]},
    {"name": "side_px", "body": "box", "type": "plane_patch", "origin": [10, -10, 0],
     "edge_u": [0, 20, 0], "edge_v": [0, 0, 10]},
    {"name": "side_nx", "body": "box", "type": "plane_patch", "origin": [-10, -10, 0],
     "edge_u": [0, 0, 10], "edge_v": [0, 20, 0]},
    {"name": "side_py", "body": "box", "type": "plane_patch", "origin": [-10, 10, 0],
     "edge_u": [0, 0, 10], "edge_v": [20, 0, 0]},
    {"name": "side_ny", "body": "box", "type": "plane_patch", "origin": [-10, -10, 0],
     "edge_u": [20, 0, 0], "edge_v": [0, 0, 10]}
  ],
  "contacts": [{"a": "floor", "b": "bottom", "kind": "unilateral", "max_contacts": 2}],
  "grasp": {"body": "box", "point": [0, 0, 5], "hold_orientation": 0.01,
            "rotational_stiffness": 0.2},
  "device": {"id": 1, "scale": 1.0, "stiffness": 300, "damping": 1.0, "max_force": 3.3,
             "max_force_rate": 500, "ramp_time": 1.0},
  "offset": {"tolerance": 0.02, "margin": 0.25}
})JSON";

// Two wire rings hooked through each other (tori of 1.2 mm major and 0.45 mm minor radius, the
// tight hooks of docs/contact.md's relative-curvature tests): the fixed one in the xy plane about
// the origin, the grasped one upright (its plane xz) touching it at their inner equators, at
// (0.75, 0, 0) mm. Pulled apart, the hooks bear on each other; turned about the line between
// their centres (the contact normal) they go from crossing towards parallel, and past 14.5° the
// one contact point becomes a saddle with a minimum either side (the pitchfork of the soak).
inline constexpr const char* kHooksScene = R"JSON({
  "name": "two hooks",
  "length_unit": "mm",
  "bodies": [
    {"name": "fixed_ring", "fixed": true},
    {"name": "ring", "position": [1.5, 0, 0], "mass": 0.001, "inertia": [2e-10, 2e-10, 2e-10]}
  ],
  "surfaces": [
    {"name": "fixed_wire", "body": "fixed_ring", "type": "torus", "major": 1.2, "minor": 0.45},
    {"name": "wire", "body": "ring", "type": "torus", "major": 1.2, "minor": 0.45,
     "quaternion": [0.7071067811865476, 0.7071067811865476, 0, 0]}
  ],
  "contacts": [{"a": "fixed_wire", "b": "wire", "kind": "unilateral", "max_contacts": 3}],
  "grasp": {"body": "ring", "point": [0, 0, 0], "hold_orientation": 0.01,
            "rotational_stiffness": 0.02},
  "device": {"id": 1, "scale": 1.0, "stiffness": 300, "damping": 1.0, "max_force": 3.3,
             "max_force_rate": 500, "ramp_time": 1.0},
  "offset": {"tolerance": 0.02, "margin": 0.25}
})JSON";

/// The kHooksScene rings' true gap (testing/torus_gap.h): their centre circles' distance less
/// both wires' radii, for the grasped ring's pose q (position, then quaternion w, x, y, z; m).
inline double HooksTrueGap(const double q[7]) {
  constexpr double kMajor = 1.2e-3, kMinor = 0.45e-3;
  // (The grasped ring's surface is turned 90° about x in its body.)
  const Eigen::Matrix3d R =
      Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix() *
      Eigen::Matrix3d(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  return CircleDistance(TorusCircle(kMajor, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()),
                        TorusCircle(kMajor, R, Eigen::Vector3d(q[0], q[1], q[2]))) -
         2 * kMinor;
}

}  // namespace tangent::testing
