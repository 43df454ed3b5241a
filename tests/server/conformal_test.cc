// Issue 33's first canonical conformal case: a rod lying in a cylindrical groove of 1 % larger
// radius (a line contact: every point along the bottom line is an extremal pair), pressed into
// it by the hand and slid along it, through the servo and the global stage. With line contacts
// (ServoOptions::line_contacts) the pair is held by three sections across the line and the hand
// feels the pressing force; as one point (the default) the continuum is not a contact the stage
// can take, and the rod is pushed through the groove.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include <Eigen/Geometry>

#include "server/global_link.h"
#include "server/scene.h"
#include "server/servo.h"
#include "testing/alloc_counter.h"
#include "testing/conformal_scenes.h"
#include "testing/drag_path.h"

namespace tangent::server {
namespace {

struct Outcome {
  double worst_violation = 0.0;
  double press_force = 0.0;  ///< mean hand force along z over 2–3 s (pressing, still)
  double slide_force_min = 1e9, slide_force_max = 0.0;  ///< |F_z| while sliding (3.5–5 s)
  double line_force = 0.0;                              ///< the line's reported load at 3 s (N)
  int line_ticks = 0;                                   ///< device steps with the pair in line mode
  long slide_allocations = 0;  ///< heap allocations in the servo's ticks while sliding
  /// The rod's axis from the groove's beyond their 0.05 mm gap, from the start: into the groove
  /// when positive (nothing passes through: the stage finds the nested pair at rest).
  double worst_axis = 0.0;
  double max_force_step = 0.0;  ///< between device steps (N)
};

// The hand presses 2 mm down from 1 s (0.6 N at 300 N/m), then from 3 s slides ±5 mm along the
// groove; 1 kHz device states, four servo ticks each, a global pass per device step.
Outcome Drive(bool lines, double seconds) {
  auto scene = ParseScene(testing::kGrooveScene, "groove.json");
  ServoOptions options;
  options.line_contacts = lines;
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  Outcome out;
  int64_t now = 1'000'000'000;
  int pressed = 0;
  double last_fz = 0.0;
  for (int k = 1; k <= static_cast<int>(seconds * 1000); ++k) {
    const double t = 1e-3 * k;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (t > 1.0) p.z() = -2e-3 * std::min(1.0, t - 1.0);
    if (t > 3.0) p.x() = 5e-3 * std::sin(1.5 * (t - 3.0));
    const DeviceSample s = bench::HandSample(k, now, p);
    const bool sliding = t > 3.5;
    const long before = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += 250'000;
      out.worst_violation = std::max(out.worst_violation, r.violation);
    }
    if (sliding) out.slide_allocations += testing::AllocationCount() - before;
    servo.FillSnapshot(&snap);
    link.Pass(snap, [&](const ContactEventMsg& m) { servo.Apply(m); });
    servo.AdoptClearances(link.clearances());
    const double fz = r.wrench.force[2];
    if (t > 2.0 && t <= 3.0) {
      out.press_force += fz;
      ++pressed;
    }
    if (sliding) {
      out.slide_force_min = std::min(out.slide_force_min, fz);
      out.slide_force_max = std::max(out.slide_force_max, fz);
    }
    out.line_ticks += servo.lines().pairs() > 0 && servo.lines().line(0);
    const int rod = 1;
    out.worst_axis = std::max(out.worst_axis, std::hypot(snap.q[rod][1], snap.q[rod][2]) - 0.05e-3);
    out.max_force_step = std::max(out.max_force_step, std::abs(fz - last_fz));
    last_fz = fz;
    if (k == 3000) {
      for (int c = 0; c < snap.num_contacts; ++c) out.line_force += snap.contacts[c].force;
    }
    if (lines && k % 250 == 0 && servo.lines().line(0)) {
      const Eigen::Vector3d f = servo.LineLoads(0);
      std::printf("  %.2f s: section loads %.4f %.4f %.4f N\n", t, f[1], f[0], f[2]);
    }
  }
  if (pressed > 0) out.press_force /= pressed;
  std::printf(
      "%s: worst violation %.1e m, pressing %.4f N (line's load %.4f N), sliding %.4f to %.4f N, "
      "line mode %d of %d device steps, %ld allocations while sliding, rod beyond the gap %.1e m, "
      "largest force step %.4f N\n",
      lines ? "line contacts" : "one point", out.worst_violation, out.press_force, out.line_force,
      out.slide_force_min, out.slide_force_max, out.line_ticks, static_cast<int>(seconds * 1000),
      out.slide_allocations, out.worst_axis, out.max_force_step);
  return out;
}

TEST(ConformalTest, ARodPressedIntoAGrooveAndSlidAlongItIsHeldAsALine) {
  const Outcome run = Drive(true, 5.0);
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_NEAR(run.press_force, 0.6, 0.006);  // k x 2 mm, to 1 %
  EXPECT_NEAR(run.line_force, 0.6, 0.006);   // carried by the line's sections
  EXPECT_GT(run.slide_force_min, 0.594);     // still pressed while it slides
  EXPECT_LT(run.slide_force_max, 0.606);
  EXPECT_GT(run.line_ticks, 3500);
  EXPECT_EQ(run.slide_allocations, 0);
  EXPECT_LE(run.worst_axis, 1e-6);      // never into the groove's wall
  EXPECT_LE(run.max_force_step, 0.05);  // the press's 0.3 N/s, not a contact found late
}

TEST(ConformalTest, AsOnePointTheGrooveDoesNotHoldTheRod) {
  // The default model: the continuum is no contact the global stage takes, so nothing resists
  // the press and the hand feels nothing (what the line model above is for).
  const Outcome run = Drive(false, 3.0);
  EXPECT_LT(std::abs(run.press_force), 0.1);
  EXPECT_EQ(run.line_ticks, 0);
}

// Issue 33's second canonical case: a ball in a spherical socket of 1 % larger radius
// (testing/conformal_scenes.h), pressed, turned and pushed round by the hand.
struct SocketOutcome {
  double worst_violation = 0.0;
  double worst_centre = 0.0;  ///< the ball's centre from the socket's beyond the 0.05 mm gap
  double press_force = 0.0;   ///< mean F_z pressed and still (2–3 s)
  double turn_force_min = 1e9, turn_force_max = 0.0;  ///< F_z while turning (3.5–5 s)
  double worst_push_error = 0.0;  ///< |F − expected| while pushed round (6–8 s)
  double max_force_step = 0.0;
  double turned = 0.0;   ///< the ball's largest turn from its start (rad)
  long allocations = 0;  ///< in the servo's ticks from 3.5 s
  int solves = 0, tracked = 0;
};

// 1 kHz device states, four servo ticks each. From 1 s the hand presses 2 mm down; from 3 s it
// turns ±60° about x; from 5 s it pushes round a 3 mm circle in the horizontal plane, still 2 mm
// down.
SocketOutcome DriveSocket() {
  auto scene = ParseScene(testing::kSocketScene, "socket.json");
  ServoOptions options;
  options.dof = 6;  // the ball turns with the hand
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  SocketOutcome out;
  int64_t now = 1'000'000'000;
  int pressed = 0;
  const int ball = scene->BodyIndex("ball");
  const double k = 300.0, gap = 0.05e-3;
  Eigen::Vector3d last_force = Eigen::Vector3d::Zero();
  for (int step = 1; step <= 8000; ++step) {
    const double t = 1e-3 * step;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (t > 1.0) p.z() = -2e-3 * std::min(1.0, t - 1.0);
    double angle = 0.0;
    if (t > 3.0 && t <= 5.0)
      angle = (std::numbers::pi / 3) * std::sin(std::numbers::pi * (t - 3.0));
    if (t > 5.0) {
      const double a = 2 * std::numbers::pi * (t - 5.0) / 3.0, rise = std::min(1.0, t - 5.0);
      p.x() = 3e-3 * rise * std::cos(a);
      p.y() = 3e-3 * rise * std::sin(a);
    }
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()));
    const DeviceSample s = bench::HandSample(step, now, p, q);
    const long before = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += 250'000;
      if (t > 1.5) out.worst_violation = std::max(out.worst_violation, r.violation);
      out.solves += r.solves;
      out.tracked += r.tracked;
    }
    if (t > 3.5) out.allocations += testing::AllocationCount() - before;
    servo.FillSnapshot(&snap);
    // A pass every 4 ms (the nested parts' offsets overlap everywhere: 1.5 ms a pass).
    if (step % 4 == 0) {
      link.Pass(snap, [&](const ContactEventMsg& m) { servo.Apply(m); });
      servo.AdoptClearances(link.clearances());
    }
    const Eigen::Vector3d f(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
    out.max_force_step = std::max(out.max_force_step, (f - last_force).norm());
    last_force = f;
    const Eigen::Vector3d centre(snap.q[ball][0], snap.q[ball][1], snap.q[ball][2]);
    out.worst_centre = std::max(out.worst_centre, centre.norm() - gap);
    const Eigen::Quaterniond turn(snap.q[ball][3], snap.q[ball][4], snap.q[ball][5],
                                  snap.q[ball][6]);
    out.turned =
        std::max(out.turned, turn.normalized().angularDistance(Eigen::Quaterniond::Identity()));
    if (t > 2.0 && t <= 3.0) {
      out.press_force += f.z();
      ++pressed;
    }
    if (t > 3.5 && t <= 5.0) {
      out.turn_force_min = std::min(out.turn_force_min, f.z());
      out.turn_force_max = std::max(out.turn_force_max, f.z());
    }
    if (t > 6.0) {
      // The hand's target is the grasp point at rest (the device's origin, gap below the
      // socket's centre) moved by p; the ball's centre stops gap from the socket's, towards it.
      const Eigen::Vector3d target = p - Eigen::Vector3d(0, 0, gap);
      // And the coupling's damping (1 N s/m) against the hand's speed round the circle.
      const double a = 2 * std::numbers::pi * (t - 5.0) / 3.0, w = 2 * std::numbers::pi / 3.0;
      const Eigen::Vector3d velocity(-3e-3 * w * std::sin(a), 3e-3 * w * std::cos(a), 0.0);
      const Eigen::Vector3d expected =
          -k * (target.norm() - gap) * target.normalized() - 1.0 * velocity;
      out.worst_push_error = std::max(out.worst_push_error, (f - expected).norm());
    }
  }
  if (pressed > 0) out.press_force /= pressed;
  std::printf(
      "ball in a socket: worst violation %.1e m, centre beyond the gap %.1e m, pressing %.4f N, "
      "turning (%.0f deg) %.4f to %.4f N, pushed round: force off k (|target| - gap) + damping by "
      "%.4f N, "
      "largest force step %.4f N, %ld allocations from 3.5 s, contact evaluations %d tracked, "
      "%d solved\n",
      out.worst_violation, out.worst_centre, out.press_force, out.turned * 180 / std::numbers::pi,
      out.turn_force_min, out.turn_force_max, out.worst_push_error, out.max_force_step,
      out.allocations, out.tracked, out.solves);
  return out;
}

TEST(ConformalTest, ABallInASocketIsHeldPressedTurnedAndPushedRound) {
  const SocketOutcome run = DriveSocket();
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_LE(run.worst_centre, 1e-6);         // never through the socket
  EXPECT_NEAR(run.press_force, 0.6, 0.006);  // k x 2 mm
  EXPECT_GT(run.turn_force_min, 0.594);      // still pressed while it turns
  EXPECT_LT(run.turn_force_max, 0.606);
  EXPECT_GT(run.turned, 0.9);              // it did turn (60° asked)
  EXPECT_LT(run.worst_push_error, 0.006);  // 1 % of the press
  EXPECT_LE(run.max_force_step, 0.5);      // the rate limit: 500 N/s over a 1 ms device step
  EXPECT_EQ(run.allocations, 0);
}

}  // namespace
}  // namespace tangent::server
