#pragma once

// Ground truth for scenes of wire rings (tori): the gap between two tori's tubes is the least
// distance between their centre circles less both tube radii, exactly, wherever the tubes do
// not reach past their circles' axes. It needs nothing of the NURBS surfaces or of the contact
// code it checks: a grid over both circles' angles, refined by zooming in on the least sample.

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Core>

namespace tangent::testing {

/// A circle in space: centre, two orthonormal directions spanning its plane, radius.
struct Circle {
  Eigen::Vector3d centre, e1, e2;
  double radius = 0.0;
  Eigen::Vector3d At(double t) const {
    return centre + radius * (std::cos(t) * e1 + std::sin(t) * e2);
  }
};

/// The least distance between two circles: a 180 x 180 grid of their angles, then six zooms of
/// a 21 x 21 grid round the least sample (each a tenth of the last's spacing).
inline double CircleDistance(const Circle& a, const Circle& b) {
  auto d2 = [&](double s, double t) { return (a.At(s) - b.At(t)).squaredNorm(); };
  constexpr int kGrid = 180;
  double step = 2.0 * std::numbers::pi / kGrid, best = INFINITY, bs = 0.0, bt = 0.0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const double v = d2(i * step, j * step);
      if (v < best) best = v, bs = i * step, bt = j * step;
    }
  }
  for (int zoom = 0; zoom < 6; ++zoom) {
    const double s0 = bs, t0 = bt;
    for (int i = -10; i <= 10; ++i) {
      for (int j = -10; j <= 10; ++j) {
        const double s = s0 + 0.1 * i * step, t = t0 + 0.1 * j * step;
        const double v = d2(s, t);
        if (v < best) best = v, bs = s, bt = t;
      }
    }
    step *= 0.1;
  }
  return std::sqrt(best);
}

/// The centre circle of a torus about its frame's z axis (nurbs::MakeTorus), placed by the
/// rotation R and translation p of that frame in the world.
inline Circle TorusCircle(double major, const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  return {p, R.col(0), R.col(1), major};
}

}  // namespace tangent::testing
