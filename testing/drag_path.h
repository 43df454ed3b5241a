#pragma once

// The hand path of the servo benchmarks and tests (the device position, no device dynamics):
// lift 6 mm along +y over 2 s, then circles of 4 mm radius in the x–y plane, 5 s per turn.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "server/servo.h"

namespace tangent::bench {

/// A real-time run's timing offline (chain_soak and hooks_turn --jitter SEED): each servo tick
/// 250 µs ± 20 %, each global pass skipped with probability 0.2. Seed 0: none (every tick
/// 250 µs, every pass run).
class TimingJitter {
 public:
  explicit TimingJitter(int seed) : on_(seed != 0), rng_(static_cast<unsigned>(seed)) {}
  /// The next tick's time step (ns).
  int64_t TickNs() { return on_ ? 250'000 + static_cast<int64_t>(tick_(rng_)) : 250'000; }
  bool SkipPass() { return on_ && skip_(rng_); }

 private:
  bool on_;
  std::mt19937 rng_;
  std::uniform_real_distribution<double> tick_{-50'000.0, 50'000.0};
  std::bernoulli_distribution skip_{0.2};
};

inline Eigen::Vector3d DragPath(double t) {
  const double lift = 6e-3 * std::min(1.0, t / 2.0);
  const double a = 2 * std::numbers::pi * std::max(0.0, t - 2.0) / 5.0;
  return {4e-3 * std::sin(a), lift + 4e-3 * (std::cos(a) - 1.0), 0.0};
}

/// A device state with the hand at `position` (device frame, m) turned by `orientation`,
/// received at now_ns.
inline server::DeviceSample HandSample(
    int64_t seq, int64_t now_ns, const Eigen::Vector3d& position,
    const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity()) {
  server::DeviceSample s;
  s.seq = seq;
  s.utime = now_ns / 1000;
  s.received_ns = now_ns;
  for (int i = 0; i < 3; ++i) s.position[i] = position[i];
  s.orientation[0] = orientation.w();
  s.orientation[1] = orientation.x();
  s.orientation[2] = orientation.y();
  s.orientation[3] = orientation.z();
  return s;
}

/// The hand of issue 33's fourth canonical case (testing/conformal_scenes.h, kHooksScene): at
/// rest for 1 s, pulling 2 mm along +x over the next second, then from 3 s turning about x,
/// ±40° in a sine of `period` s (8 s: at most 31.4°/s). Device state `seq` (1 kHz: t = seq ms),
/// received at now_ns.
inline server::DeviceSample HooksHandSample(int64_t seq, int64_t now_ns, double period = 8.0) {
  const double t = 1e-3 * static_cast<double>(seq);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  if (t > 1.0) p.x() = 2e-3 * std::min(1.0, t - 1.0);
  const double angle =
      t > 3.0 ? (40 * std::numbers::pi / 180) * std::sin(2 * std::numbers::pi * (t - 3.0) / period)
              : 0.0;
  return HandSample(seq, now_ns, p,
                    Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX())));
}

/// The device state on that path at time t (s), received at now_ns.
inline server::DeviceSample DragSample(int64_t seq, double t, int64_t now_ns) {
  return HandSample(seq, now_ns, DragPath(t));
}

}  // namespace tangent::bench
