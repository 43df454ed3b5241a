#pragma once

// The hand path of the servo benchmarks and tests (the device position, no device dynamics):
// lift 6 mm along +y over 2 s, then circles of 4 mm radius in the x–y plane, 5 s per turn.

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Core>

#include "server/servo.h"

namespace tangent::bench {

inline Eigen::Vector3d DragPath(double t) {
  const double lift = 6e-3 * std::min(1.0, t / 2.0);
  const double a = 2 * std::numbers::pi * std::max(0.0, t - 2.0) / 5.0;
  return {4e-3 * std::sin(a), lift + 4e-3 * (std::cos(a) - 1.0), 0.0};
}

/// The device state on that path at time t (s), received at now_ns.
inline server::DeviceSample DragSample(int64_t seq, double t, int64_t now_ns) {
  server::DeviceSample s;
  s.seq = seq;
  s.utime = now_ns / 1000;
  s.received_ns = now_ns;
  const Eigen::Vector3d hand = DragPath(t);
  for (int i = 0; i < 3; ++i) s.position[i] = hand[i];
  return s;
}

}  // namespace tangent::bench
