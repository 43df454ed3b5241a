#pragma once

// Three paperclips in a chain (seed 001 Fig. 1, 3): clip 0 in the x–y plane, clip 1 turned 90°
// about y with its small bend hooked on clip 0's top point, clip 2 in the x–y plane again with
// its small bend hooked on clip 1's top point. Each hook touches (wire centre lines 0.9 mm
// apart). Clip frames are those of nurbs::PaperclipPath (start at the origin heading +y).

#include <Eigen/Geometry>

#include "contact/placed.h"

namespace tangent::contact::testing {

struct PaperclipChainPoses {
  static constexpr double mm = 1e-3;
  Vector7d clip[3];
  Eigen::Vector3d hook01, hook12;  ///< world points where the hooks touch

  PaperclipChainPoses() {
    // A small bend (centre (−1.75, −6) mm, radius 3.25 mm) hangs on the top point (−2.5, 23) mm
    // of the clip below; its inside touches that wire 2.35 mm from the bend's centre.
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d top(-2.5 * mm, 23 * mm, 0), bend(-1.75 * mm, -6 * mm, 0);
    const Eigen::Vector3d inside(0, -2.35 * mm, 0);
    const Eigen::Vector3d t1 = top - inside - turn * bend;
    hook01 = top;
    hook12 = turn * top + t1;
    const Eigen::Vector3d t2 = hook12 - inside - bend;
    clip[0] << 0, 0, 0, 1, 0, 0, 0;
    clip[1] << t1, turn.w(), turn.x(), turn.y(), turn.z();
    clip[2] << t2, 1, 0, 0, 0;
  }
};

}  // namespace tangent::contact::testing
