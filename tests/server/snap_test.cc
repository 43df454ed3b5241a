// Snapping parts (docs/stability.md, "Snapping parts"; ServoOptions::max_part_speed): a part
// one of whose contacts is near a pitchfork of its distance moves no point faster than the
// bound in a tick's solve. Issue 33's fourth canonical case (testing/conformal_scenes.h,
// kHooksScene) turned through its pitchfork by a hand faster than the bound set here: every
// bounded tick keeps to the bound, measured as the solver measures it (the clearance guard's
// μ_b: the ring's translation plus its turn's chord times its reach), and without the bound the
// same hand moves the ring faster than it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include <Eigen/Core>

#include "server/global_link.h"
#include "server/scene.h"
#include "server/servo.h"
#include "testing/alloc_counter.h"
#include "testing/conformal_scenes.h"
#include "testing/drag_path.h"

namespace tangent::server {
namespace {

constexpr double kTick = 250e-6;  // s: four servo ticks per 1 ms device state

struct SnapOutcome {
  int bounded_ticks = 0;
  double worst_bounded_ratio = 0.0;  ///< the ring's motion over the bound, in bounded ticks
  /// Ticks of the turn (from 3 s) in which the ring moved more than `max_part_speed` allows.
  int faster_ticks = 0;
  double worst_violation = 0.0;
  double true_gap = 1e9;  ///< testing::HooksTrueGap, every 10 ms
  long allocations = 0;   ///< in the servo's ticks from the turn's start
};

// The hooks turned ±40° over 4 s from 3 s (at most 62.8°/s: the ring's points at its reach move
// up to 1.8 mm/s), for 5 s: through the pitchfork at 14.5° and back. A global pass every 1 ms.
// `max_part_speed`: the servo's (0: no bound); `bound`: the speed the ticks are measured against.
SnapOutcome TurnHooks(double max_part_speed, double bound) {
  const auto scene = ParseScene(testing::kHooksScene, "hooks.json");
  ServoOptions options;
  options.dof = 6;
  options.max_part_speed = max_part_speed;
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  SnapOutcome out;
  const int ring = scene->BodyIndex("ring");
  const Eigen::VectorXd no_step = Eigen::VectorXd::Zero(servo.q().size());
  Eigen::VectorXd before_tick = servo.q();
  int64_t now = 1'000'000'000;
  for (int step = 1; step <= 5000; ++step) {
    const DeviceSample s = bench::HooksHandSample(step, now, /*period=*/4.0);
    const long allocations = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      before_tick = servo.q();
      servo.Tick(&s, now, &r);
      now += 250'000;
      out.worst_violation = std::max(out.worst_violation, r.violation);
      if (step == 1 && tick == 0) continue;  // (the first tick settles: no time step yet)
      const double moved = servo.clearance_guard().Motion(ring, before_tick, servo.q(), no_step, 0);
      if (step > 3000 && moved > bound * kTick) ++out.faster_ticks;
      if (!r.bounded) continue;
      ++out.bounded_ticks;
      out.worst_bounded_ratio = std::max(out.worst_bounded_ratio, moved / (bound * kTick));
    }
    if (step > 3000) out.allocations += testing::AllocationCount() - allocations;
    servo.FillSnapshot(&snap);
    link.PassInto(&servo, snap);
    if (step % 10 == 0) out.true_gap = std::min(out.true_gap, testing::HooksTrueGap(snap.q[ring]));
  }
  std::printf(
      "max_part_speed %.1e m/s: %d bounded ticks, their motion at most %.6f of %.1e m/s; %d "
      "ticks of the turn faster; worst violation %.1e m; true gap at least %.1e m; %ld "
      "allocations\n",
      max_part_speed, out.bounded_ticks, out.worst_bounded_ratio, bound, out.faster_ticks,
      out.worst_violation, out.true_gap, out.allocations);
  return out;
}

TEST(SnapTest, PartsNearAPitchforkMoveNoFasterThanTheBoundAndStayHooked) {
  const double speed = 1e-3;  // m/s: below the hand's 1.8 mm/s at the ring's reach
  const SnapOutcome bounded = TurnHooks(speed, speed);
  // The pitchfork is passed twice (at 14.5° going out and coming back), and the contacts stay
  // near it for many ticks each way.
  EXPECT_GT(bounded.bounded_ticks, 100);
  // Every bounded tick keeps to the bound (the bisection's 2⁻²⁰ rounds inward; the solve's
  // finishing correction, which is not bounded, moves by the constraint tolerance's order).
  EXPECT_LE(bounded.worst_bounded_ratio, 1.0 + 1e-3);
  EXPECT_LE(bounded.worst_violation, 1e-6);
  EXPECT_GE(bounded.true_gap, -1e-6);
  EXPECT_EQ(bounded.allocations, 0);

  // Without the bound the same hand turns the ring faster than the bound allows: the bound, not
  // the hand, is what kept it.
  const SnapOutcome free = TurnHooks(0.0, speed);
  EXPECT_EQ(free.bounded_ticks, 0);
  EXPECT_GT(free.faster_ticks, 1000);
}

}  // namespace
}  // namespace tangent::server
