// The servo's safety rules without threads (issue 12, docs/server.md "Faults"): a non-finite or
// absurd value injected at each stage of a tick (device state, goal, solver result, coupling)
// makes that tick a fault: the scene is restored, the force goes to zero within the rate limit,
// nothing allocates, and the next ticks recover by themselves. A new session starts from zero
// force; a jump of the device is followed at bounded speed; the force-rate limit runs on the
// server's clock, whatever the client's says.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "server/servo.h"
#include "testing/alloc_counter.h"

namespace tangent::server {
namespace {

constexpr double mm = 1e-3;
constexpr int64_t kTick = 250'000;  // ns: 4 kHz servo
constexpr int kTicksPerState = 4;   // 1 kHz device

std::unique_ptr<Scene> Load(const std::string& name) {
  return LoadScene(std::string(TANGENT_SCENES_DIR) + "/" + name + ".json");
}

Eigen::Vector3d Force(const WrenchSample& w) { return {w.force[0], w.force[1], w.force[2]}; }

/// Drives a servo with 1 kHz device states, four ticks each, and checks every wrench it sends:
/// finite, within max_force, and within the rate limit of the previous one on the server clock.
struct Rig {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<ServoLoop> servo;
  int64_t now = 1'000'000'000;
  int64_t seq = 0, accepted = 0, session_index = 1;
  TickResult r;
  WrenchSample last;
  bool have_last = false;
  double worst_violation = 0.0, worst_step_excess = 0.0, max_force = 0.0;
  int faults = 0, non_finite = 0, answers = 0;

  explicit Rig(const std::string& name) : scene(Load(name)) {
    servo = std::make_unique<ServoLoop>(*scene, ServoOptions{});
  }

  DeviceSample State(const Eigen::Vector3d& p) {
    DeviceSample s;
    s.seq = ++seq;
    s.utime = now / 1000;
    s.received_ns = now;
    s.session_index = session_index;
    s.accepted = ++accepted;
    for (int i = 0; i < 3; ++i) s.position[i] = p[i];
    return s;
  }
  /// One device state and its four ticks.
  void Step(const DeviceSample& s) {
    for (int k = 0; k < kTicksPerState; ++k) {
      servo->Tick(&s, now, &r);
      now += kTick;
      faults += r.fault;
      worst_violation = std::max(worst_violation, r.violation);
      if (r.answered) Check(r.wrench);
    }
  }
  void Run(const Eigen::Vector3d& p, int states) {
    for (int k = 0; k < states; ++k) Step(State(p));
  }
  void Check(const WrenchSample& w) {
    ++answers;
    const Eigen::Vector3d f = Force(w);
    if (!f.allFinite()) ++non_finite;
    max_force = std::max(max_force, f.norm());
    if (have_last && last.device_id == w.device_id) {
      const double dt = 1e-6 * static_cast<double>(w.server_utime - last.server_utime) + 1e-6;
      const double allowed = scene->device.max_force_rate * dt;
      worst_step_excess = std::max(worst_step_excess, (f - Force(last)).norm() - allowed);
    }
    last = w;
    have_last = true;
  }
};

struct FaultCase {
  InjectedFault::Stage stage;
  double value;
  const char* name;
};

TEST(ServoSafetyTest, AnInjectedFaultAtEachStageRestoresTheSceneAndRecovers) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const FaultCase cases[] = {
      {InjectedFault::kDeviceState, nan, "device state NaN"},
      {InjectedFault::kDeviceState, inf, "device state inf"},
      {InjectedFault::kDeviceState, 1e308, "device state 1e308 m"},
      {InjectedFault::kDeviceState, 1e9, "device state 1e9 m"},
      {InjectedFault::kGoal, nan, "goal NaN"},
      {InjectedFault::kGoal, -inf, "goal -inf"},
      {InjectedFault::kGoal, 1e308, "goal 1e308 m"},
      {InjectedFault::kGoal, 1e9, "goal 1e9 m"},
      {InjectedFault::kSolverResult, nan, "solver result NaN"},
      {InjectedFault::kSolverResult, inf, "solver result inf"},
      {InjectedFault::kSolverResult, 1e308, "solver result 1e308"},
      {InjectedFault::kSolverResult, 1e9, "solver result 1e9 m"},
      {InjectedFault::kCoupling, nan, "coupling NaN"},
      {InjectedFault::kCoupling, inf, "coupling inf"},
      {InjectedFault::kCoupling, 1e308, "coupling 1e308 N"},
      {InjectedFault::kCoupling, 1e9, "coupling 1e9 N"},
  };
  for (const char* scene : {"paperclips", "fourbar_floating"}) {
    Rig rig(scene);
    // A pull the scene resists (the hooks hold the chain; the four-bar's finger on the pad).
    const Eigen::Vector3d pulled = std::string(scene) == "paperclips"
                                       ? Eigen::Vector3d(0, 4 * mm, 0)
                                       : Eigen::Vector3d(30 * mm, 0, 0);
    rig.Run(pulled, 1500);  // ramped up and pulling
    const double before = Force(rig.r.wrench).norm();
    ASSERT_GT(before, 0.3) << scene;
    for (const FaultCase& c : cases) {
      SCOPED_TRACE(std::string(scene) + ": " + c.name);
      const Eigen::VectorXd q_before = rig.servo->q();
      const int faults_before = rig.faults;
      const DeviceSample s = rig.State(pulled);
      rig.servo->InjectFault({c.stage, c.value});
      const long allocations_before = tangent::testing::AllocationCount();
      rig.servo->Tick(&s, rig.now, &rig.r);  // the faulty tick answers s
      rig.now += kTick;
      const long allocations = tangent::testing::AllocationCount() - allocations_before;
      EXPECT_EQ(allocations, 0);
      EXPECT_TRUE(rig.r.fault);
      ASSERT_TRUE(rig.r.answered);
      EXPECT_EQ(rig.r.wrench.state, kFault);
      rig.faults += rig.r.fault;
      rig.Check(rig.r.wrench);
      // The scene is the last good one (the hand held still: the same configuration).
      EXPECT_TRUE(rig.servo->q().allFinite());
      EXPECT_LE((rig.servo->q() - q_before).norm(), 1e-6);
      // The force heads to zero within the rate limit: one answer's step, no jump.
      EXPECT_LT(Force(rig.r.wrench).norm(), before);
      EXPECT_GE(Force(rig.r.wrench).norm(),
                before - rig.scene->device.max_force_rate * 2e-3 - 1e-9);
      // The following ticks recover by themselves: no further fault, exact constraints, and
      // the force ramps back (ramp_time 1 s).
      rig.worst_violation = 0.0;
      rig.Run(pulled, 1200);
      EXPECT_EQ(rig.faults, faults_before + 1);
      EXPECT_LE(rig.worst_violation, 1e-9);
      EXPECT_NEAR(Force(rig.r.wrench).norm(), before, 0.05 * before);
    }
    std::printf(
        "%s: %d faults injected, %d answers, 0 non-finite expected (%d), max |F| %.3f N, "
        "worst rate-limit excess %.2e N\n",
        scene, rig.faults, rig.answers, rig.non_finite, rig.max_force, rig.worst_step_excess);
    EXPECT_EQ(rig.non_finite, 0);
    EXPECT_LE(rig.max_force, rig.scene->device.max_force + 1e-12);
    EXPECT_LE(rig.worst_step_excess, 1e-9);
  }
}

TEST(ServoSafetyTest, AJumpIsFollowedAtBoundedSpeedAndTheSceneStaysExact) {
  for (const char* scene : {"paperclips", "fourbar_floating"}) {
    SCOPED_TRACE(scene);
    Rig rig(scene);
    rig.Run(Eigen::Vector3d::Zero(), 1200);
    rig.worst_violation = 0.0;
    // 9 cm in one state (inside the workspace), held for 0.3 s.
    const Eigen::Vector3d far(0.09, 0, 0);
    Eigen::Vector3d target = rig.servo->GraspTarget();
    double worst_target_step = 0.0, worst_reach = 0.0;
    for (int k = 0; k < 300; ++k) {
      const DeviceSample s = rig.State(far);
      for (int t = 0; t < kTicksPerState; ++t) {
        rig.servo->Tick(&s, rig.now, &rig.r);
        rig.now += kTick;
        rig.worst_violation = std::max(rig.worst_violation, rig.r.violation);
        if (rig.r.answered) rig.Check(rig.r.wrench);
        const Eigen::Vector3d next = rig.servo->GraspTarget();
        worst_target_step = std::max(worst_target_step, (next - target).norm());
        target = next;
        worst_reach = std::max(worst_reach, (next - rig.servo->GraspPoint()).norm());
      }
    }
    const double allowed = rig.scene->device.follow_speed * rig.scene->device.scale * 1e-9 *
                           static_cast<double>(kTick);
    std::printf(
        "%s: 9 cm jump: largest target step %.3e m per tick (allowed %.3e), worst "
        "violation %.1e, max |F| %.2f N, worst rate-limit excess %.1e N\n",
        scene, worst_target_step, allowed, rig.worst_violation, rig.max_force,
        rig.worst_step_excess);
    EXPECT_LE(worst_target_step, allowed * (1 + 1e-9));
    // A saturated coupling for the scene too: the target never leads the grasp point by more
    // than max_force / k (the parts are pulled with at most what the hand feels). Measured after
    // the solve, so the grasp may have moved by its step in that tick.
    const double reach =
        rig.scene->device.scale * rig.scene->device.max_force / rig.scene->device.stiffness;
    std::printf("%s: target ahead of the grasp point by at most %.3e m (saturation %.3e m)\n",
                scene, worst_reach, reach);
    EXPECT_LE(worst_reach, reach + allowed);
    EXPECT_LE(rig.worst_violation, 1e-6);
    EXPECT_EQ(rig.faults, 0);
    EXPECT_LE(rig.worst_step_excess, 1e-9);
    EXPECT_LE(rig.max_force, rig.scene->device.max_force + 1e-12);
  }
}

TEST(ServoSafetyTest, TheRateLimitRunsOnTheServersClock) {
  Rig rig("paperclips");
  rig.Run(Eigen::Vector3d::Zero(), 1200);
  // The client's clock leaps a second (and back) between states; the hand pulls 5 cm at once,
  // which saturates the coupling: each answer's step stays within rate x 1 ms of server time.
  for (int k = 0; k < 200; ++k) {
    DeviceSample s = rig.State(Eigen::Vector3d(0, 0.05, 0));
    s.utime += (k % 2 ? 1 : -1) * 1'000'000;
    rig.Step(s);
  }
  EXPECT_LE(rig.worst_step_excess, 1e-9);
  EXPECT_EQ(rig.non_finite, 0);
  EXPECT_NEAR(rig.max_force, rig.scene->device.max_force, 1e-9);  // saturated, never above
}

TEST(ServoSafetyTest, ANewSessionStartsFromZeroForceWithAFreshRamp) {
  Rig rig("paperclips");
  rig.Run(Eigen::Vector3d(0, 4 * mm, 0), 1500);
  ASSERT_GT(Force(rig.r.wrench).norm(), 0.3);
  // A restarted client: seq from 1, a new session (the bridge's session index moves on).
  rig.session_index = 2;
  rig.seq = 0;
  const DeviceSample s = rig.State(Eigen::Vector3d(0, 4 * mm, 0));
  rig.servo->Tick(&s, rig.now, &rig.r);
  rig.now += kTick;
  ASSERT_TRUE(rig.r.answered);
  EXPECT_TRUE(rig.r.new_session);
  EXPECT_EQ(rig.r.wrench.seq, 1);
  EXPECT_EQ(rig.r.wrench.state, kRampingUp);
  EXPECT_EQ(Force(rig.r.wrench).norm(), 0.0);
  rig.have_last = false;  // a new session's wrenches are continuous among themselves
  rig.Run(Eigen::Vector3d(0, 4 * mm, 0), 1200);
  EXPECT_EQ(rig.r.wrench.state, kRunning);  // within one ramp time (1 s) and a little
  EXPECT_GT(Force(rig.r.wrench).norm(), 0.3);
  EXPECT_LE(rig.worst_step_excess, 1e-9);
}

TEST(ServoSafetyTest, AcceptedStatesTheServoNeverTookAreCounted) {
  Rig rig("paperclips");
  rig.Run(Eigen::Vector3d::Zero(), 10);
  rig.accepted += 3;  // three accepted states replaced in the mailbox before a tick took them
  const DeviceSample s = rig.State(Eigen::Vector3d::Zero());
  rig.servo->Tick(&s, rig.now, &rig.r);
  EXPECT_TRUE(rig.r.answered);
  EXPECT_EQ(rig.r.unanswered, 3);
}

}  // namespace
}  // namespace tangent::server
