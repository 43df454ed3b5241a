#pragma once

// Drives a scene's servo and global stage along a hand path in one thread, without device
// dynamics (the live demo's hand path as device states): 1 kHz states, 4 servo ticks each, a
// global pass every 4 states. Counts what every such test needs (violation, force, its largest
// step, allocations on the servo's ticks) and hands each state's snapshot to the caller.

#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <Eigen/Core>

#include "server/global_link.h"
#include "server/phantom.h"
#include "server/servo.h"
#include "testing/alloc_counter.h"

namespace tangent::server {

struct HandDrive {
  double worst_violation = 0.0, max_force = 0.0, max_force_step = 0.0;
  int ticks = 0, events = 0;
  /// Tracker steps that lost their contact (TickResult::lost: each re-solved in full).
  int64_t lost = 0;
  double max_force_step_at = 0.0;  ///< the path's time (s) of the largest step
  bool all_finite = true;
  long allocations = 0;
  double tick_seconds = 0.0, pass_seconds = 0.0;
};

/// Runs `states` device states of the path in `csv` (scenes/NAME.path.csv); `each` sees the
/// servo's snapshot after each state's ticks.
inline HandDrive DriveAlongPath(const Scene& scene, const std::string& csv, int states,
                                const std::function<void(const Snapshot&)>& each) {
  std::ifstream f(csv);
  std::stringstream text;
  text << f.rdbuf();
  const HandTrajectory hand = HandTrajectory::FromCsv(text.str(), csv);
  ServoLoop servo(scene, ServoOptions{});
  GlobalLink link(servo);
  auto seconds = [](std::chrono::steady_clock::time_point from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  };
  HandDrive run;
  Snapshot snap;
  TickResult r;
  int64_t now = 1'000'000'000, seq = 0;
  Eigen::Vector3d last_force = Eigen::Vector3d::Zero();
  for (int k = 0; k < states; ++k) {
    const Eigen::Vector3d p = hand.At(1e-3 * k);
    DeviceSample s;
    s.seq = ++seq;
    s.utime = now / 1000;
    s.received_ns = now;
    for (int i = 0; i < 3; ++i) s.position[i] = p[i];
    s.orientation[0] = 1.0;
    for (int tick = 0; tick < 4; ++tick) {
      const long before = tangent::testing::AllocationCount();
      const auto t0 = std::chrono::steady_clock::now();
      servo.Tick(&s, now, &r);
      run.tick_seconds += seconds(t0);
      run.allocations += tangent::testing::AllocationCount() - before;
      now += 250'000;
      ++run.ticks;
      run.worst_violation = std::max(run.worst_violation, r.violation);
      run.lost += r.lost;
      if (r.answered) {
        const Eigen::Vector3d F(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
        run.all_finite = run.all_finite && F.allFinite();
        run.max_force = std::max(run.max_force, F.norm());
        if ((F - last_force).norm() > run.max_force_step) {
          run.max_force_step = (F - last_force).norm();
          run.max_force_step_at = 1e-3 * k;
        }
        last_force = F;
      }
    }
    servo.FillSnapshot(&snap);
    each(snap);
    if (k % 4 == 3) {
      const auto t0 = std::chrono::steady_clock::now();
      link.PassInto(&servo, snap,
                    [&](const ContactEventMsg&, bool applied) { run.events += applied; });
      run.pass_seconds += seconds(t0);
    }
  }
  return run;
}

}  // namespace tangent::server
