#pragma once

// Three paperclips in a chain (seed 001 Fig. 1, 3; poses in testing/paperclip_chain.h) as
// a mechanism: clip 0 held fixed, clips 1 and 2 free. Each clip is the exact NURBS tube of
// nurbs::PaperclipPath (wire radius 0.45 mm).

#include <numbers>
#include <vector>

#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "optimizer/problem.h"
#include "testing/paperclip_chain.h"

namespace tangent::optimizer::testing {

struct PaperclipChain {
  static constexpr double mm = 1e-3;
  nurbs::NurbsSurface wire = nurbs::MakeTube(nurbs::PaperclipPath(), nurbs::kPaperclipWireRadius);
  Mechanism mechanism;
  int clip[3];
  /// World points where the hooks touch (initially): clip 0–1 and clip 1–2.
  Eigen::Vector3d hook01, hook12;

  PaperclipChain() {
    const contact::testing::PaperclipChainPoses chain;
    hook01 = chain.hook01;
    hook12 = chain.hook12;
    const double mass = 0.5e-3;  // kg: 0.9 mm steel wire, 110 mm long
    const Eigen::Matrix3d inertia =
        Eigen::Vector3d(4.5e-8, 4e-9, 4.9e-8).asDiagonal();  // kg m², about the clip frame
    for (int k = 0; k < 3; ++k) {
      Body b{"clip" + std::to_string(k)};
      b.fixed = k == 0;
      b.pose = chain.clip[k];
      b.mass = mass;
      b.inertia = inertia;
      clip[k] = mechanism.AddBody(b);
    }
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
