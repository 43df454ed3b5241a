#pragma once

// Three paperclips in a chain (seed 001 Fig. 1, 3): clip 0 held fixed, clip 1 hooked through
// clip 0's top bend, clip 2 hooked through clip 1's top bend. Each clip is the exact NURBS tube
// of nurbs::PaperclipPath (wire radius 0.45 mm). Clip frames: clip 0 in the x–y plane; clip 1
// turned 90° about y (its bends wrap clip 0's wire, which runs along x at the hook); clip 2 in
// the x–y plane again. In the initial poses each hook touches: centre lines 0.9 mm apart.

#include <numbers>
#include <vector>

#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "optimizer/problem.h"

namespace tangent::optimizer::testing {

struct PaperclipChain {
  static constexpr double mm = 1e-3;
  nurbs::NurbsSurface wire = nurbs::MakeTube(nurbs::PaperclipPath(), nurbs::kPaperclipWireRadius);
  Mechanism mechanism;
  int clip[3];
  /// World points where the hooks touch (initially): clip 0–1 and clip 1–2.
  Eigen::Vector3d hook01, hook12;

  PaperclipChain() {
    // Clip 1: its small bend (centre (−1.75, −6) mm, radius 3.25 mm in its own frame) hangs
    // on clip 0's top point (−2.5, 23, 0) mm; the bend's inside touches it 2.35 mm from its centre.
    const Eigen::Quaterniond turn(
        Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d top0(-2.5 * mm, 23 * mm, 0);
    const Eigen::Vector3d bend(-1.75 * mm, -6 * mm, 0);
    const Eigen::Vector3d inside(0, -2.35 * mm, 0);
    const Eigen::Vector3d t1 = top0 - inside - turn * bend;
    // Clip 2 hangs the same way on clip 1's top point, unrotated (clip 1's wire runs along z).
    const Eigen::Vector3d top1 = turn * top0 + t1;
    const Eigen::Vector3d t2 = top1 - inside - bend;
    hook01 = top0;
    hook12 = top1;
    const double mass = 0.5e-3;  // kg: 0.9 mm steel wire, 110 mm long
    const Eigen::Matrix3d inertia =
        Eigen::Vector3d(4.5e-8, 4e-9, 4.9e-8).asDiagonal();  // kg m², about the clip frame
    Body b0{"clip0"};
    b0.fixed = true;
    clip[0] = mechanism.AddBody(b0);
    Body b1{"clip1"}, b2{"clip2"};
    b1.pose << t1, turn.w(), turn.x(), turn.y(), turn.z();
    b2.pose << t2, 1, 0, 0, 0;
    for (Body* b : {&b1, &b2}) {
      b->mass = mass;
      b->inertia = inertia;
    }
    clip[1] = mechanism.AddBody(b1);
    clip[2] = mechanism.AddBody(b2);
  }

  /// Seed (u, v, s, t) for the contact of clips a and b near world point x: the nearest pair of
  /// samples (400 along the wire, 16 around) within 3 mm of x.
  Eigen::Vector4d Seed(const std::vector<BodyPose>& poses, int a, int b,
                       const Eigen::Vector3d& x) const {
    struct Sample {
      Eigen::Vector2d uv;
      Eigen::Vector3d p;
    };
    auto near = [&](int body) {
      std::vector<Sample> out;
      for (int i = 0; i < 400; ++i) {
        for (int j = 0; j < 16; ++j) {
          const Eigen::Vector2d uv((i + 0.5) / 400, (j + 0.5) / 16);
          const Eigen::Vector3d p =
              poses[static_cast<size_t>(body)].Point(wire.Evaluate(uv[0], uv[1], 0).S);
          if ((p - x).norm() < 3 * mm) out.push_back({uv, p});
        }
      }
      return out;
    };
    const std::vector<Sample> sa = near(a), sb = near(b);
    double best = 1e300;
    Eigen::Vector4d seed = Eigen::Vector4d::Constant(0.5);
    for (const Sample& p : sa) {
      for (const Sample& q : sb) {
        if ((p.p - q.p).squaredNorm() < best) {
          best = (p.p - q.p).squaredNorm();
          seed << p.uv, q.uv;
        }
      }
    }
    return seed;
  }
};

}  // namespace tangent::optimizer::testing
