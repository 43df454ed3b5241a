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
    link.PassInto(&servo, snap);
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

TEST(ConformalTest, AsOnePointTheGrooveHoldsTheRodOnOneRow) {
  // The default model: one row on the continuum of extremal pairs, held where its solves end
  // singular (optimizer/contacts.h, ContactSlotState::undecided). It holds the press and the
  // slide (before that hold, nothing resisted the press and the hand felt nothing); the line
  // model above shares the load along the rod instead of carrying it on one point.
  const Outcome run = Drive(false, 5.0);
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_NEAR(run.press_force, 0.6, 0.006);
  EXPECT_GT(run.slide_force_min, 0.594);
  EXPECT_LT(run.slide_force_max, 0.606);
  EXPECT_EQ(run.line_ticks, 0);
  EXPECT_EQ(run.slide_allocations, 0);
  EXPECT_LE(run.worst_axis, 1e-6);
  EXPECT_LE(run.max_force_step, 0.05);
}

// Issue 33's fourth canonical case (testing/conformal_scenes.h, kHooksScene; bench/hooks_turn):
// two wire rings hooked through each other, the free one pulled 2 mm from 1 s, then turned by
// the hand about the line between the centres, ±40° over 8 s from 3 s. At 14.5° the one
// contact point becomes a saddle with a minimum either side (a pitchfork); the rings must stay
// hooked on both.
struct HooksOutcome {
  double worst_violation = 0.0;
  double worst_x = 0.0;         ///< the ring's largest x (mm): 1.5 where the other holds it
  double pulled_force = 0.0;    ///< F_x at 3 s, before the turn
  double max_force_step = 0.0;  ///< between device steps (N)
  int most_contacts = 0;
  int most_loaded = 0;                    ///< contacts carrying more than 1 mN at once
  double peak_force[2] = {0, 0};          ///< |F| at +40° (5 s) and −40° (9 s)
  double peak_smaller_share[2] = {1, 1};  ///< the smaller of the two rows' loads over their sum
  long allocations = 0;                   ///< in the servo's ticks from 3 s
  /// The rings' least true gap (their centre circles' distance less both wires' radii,
  /// testing/torus_gap.h, every 10 ms): what the rows read cannot hide a crossing from it.
  double true_gap = 1e9;
};

// `period`: the turn's (s; ±40°, hooks_turn's --period); a global pass every `pass_every` ms.
HooksOutcome DriveHooks(double period = 8.0, int pass_every = 1) {
  const auto scene = ParseScene(testing::kHooksScene, "hooks.json");
  ServoOptions options;
  options.dof = 6;
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  HooksOutcome out;
  const int ring = scene->BodyIndex("ring");
  int64_t now = 1'000'000'000;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  for (int step = 1; step <= 11000; ++step) {
    const double t = 1e-3 * step;
    const DeviceSample s = bench::HooksHandSample(step, now, period);
    const long before = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += 250'000;
      out.worst_violation = std::max(out.worst_violation, r.violation);
    }
    if (t > 3.0) out.allocations += testing::AllocationCount() - before;
    servo.FillSnapshot(&snap);
    if (step % pass_every == 0) link.PassInto(&servo, snap);
    if (step % 10 == 0) {
      const double gap = testing::HooksTrueGap(snap.q[ring]);
      out.true_gap = std::min(out.true_gap, gap);
    }
    const Eigen::Vector3d f(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
    out.max_force_step = std::max(out.max_force_step, (f - last).norm());
    last = f;
    out.worst_x = std::max(out.worst_x, snap.q[ring][0] * 1e3);
    out.most_contacts = std::max(out.most_contacts, snap.num_contacts);
    int loaded = 0;
    for (int c = 0; c < snap.num_contacts; ++c) loaded += snap.contacts[c].force > 1e-3;
    out.most_loaded = std::max(out.most_loaded, loaded);
    if (step == 3000) out.pulled_force = f.x();
    for (int peak = 0; peak < 2; ++peak) {
      // (±40° a quarter and three quarters of a period after the turn starts at 3 s.)
      if (step != static_cast<int>(std::lround(1000 * (3.0 + (peak == 0 ? 0.25 : 0.75) * period))))
        continue;
      out.peak_force[peak] = f.norm();
      double sum = 0.0, smaller = 1e9;
      for (int c = 0; c < snap.num_contacts; ++c) {
        sum += snap.contacts[c].force;
        smaller = std::min(smaller, snap.contacts[c].force);
      }
      out.peak_smaller_share[peak] = snap.num_contacts == 2 ? smaller / sum : 0.0;
    }
  }
  std::printf(
      "hooks: worst violation %.1e m, ring x at most %.4f mm, pulled %.4f N, at ±40° |F| %.4f / "
      "%.4f N with the smaller row's share %.3f / %.3f, most contacts %d (%d loaded), largest "
      "force step %.4f N, %ld allocations, true gap at least %.1e m\n",
      out.worst_violation, out.worst_x, out.pulled_force, out.peak_force[0], out.peak_force[1],
      out.peak_smaller_share[0], out.peak_smaller_share[1], out.most_contacts, out.most_loaded,
      out.max_force_step, out.allocations, out.true_gap);
  return out;
}

TEST(ConformalTest, TwoHooksTurnedFromCrossingTowardsParallelStayHookedOnBothMinima) {
  const HooksOutcome run = DriveHooks();
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_GE(run.true_gap, -1e-6);
  // Never pulled through: the other ring holds this one at x = 1.5 mm (2 x 1.2 mm major radius
  // less 2 x 0.45 mm wire) or nearer, as the turned rings nestle.
  EXPECT_LE(run.worst_x, 1.5 + 1e-6);
  EXPECT_NEAR(run.pulled_force, -0.6, 0.001);  // k x (2 mm − 0 mm held) at 300 N/m
  // Beyond the pitchfork both minima are rows, each carrying a share of the load, the same
  // turned either way: never more than two loaded. (At the pitchfork, for a few ticks, the
  // minima's two rows are reported beside the line's middle section, which then carries
  // nothing: three reported; the line then follows one minimum and a point row the other.)
  EXPECT_EQ(run.most_loaded, 2);
  EXPECT_LE(run.most_contacts, 3);
  for (int peak = 0; peak < 2; ++peak) {
    EXPECT_GT(run.peak_force[peak], 0.6);
    EXPECT_GT(run.peak_smaller_share[peak], 0.25);
  }
  EXPECT_NEAR(run.peak_force[0], run.peak_force[1], 1e-3);
  EXPECT_LE(run.max_force_step, 0.05);
  EXPECT_EQ(run.allocations, 0);
}

// The same turn twice as fast (62.8°/s at its peak) with the global stage passing every 4 ms:
// past the pitchfork the contacts' curvature makes the Newton matrix indefinite, and damping it
// until positive definite stalled every tick at the iteration cap until the rings came apart
// (at 17° of the turn); with the indefinite matrix's own Newton step (docs/optimizer.md) they
// stay hooked and exact, by their true gap as well as by the rows.
TEST(ConformalTest, TwoHooksTurnedTwiceAsFastWithSparserPassesStayHookedAndExact) {
  const HooksOutcome run = DriveHooks(/*period=*/4.0, /*pass_every=*/4);
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_GE(run.true_gap, -1e-6);
  EXPECT_LE(run.worst_x, 1.5 + 1e-6);
  EXPECT_NEAR(run.pulled_force, -0.6, 0.001);
  for (int peak = 0; peak < 2; ++peak) EXPECT_GT(run.peak_force[peak], 0.6);
  EXPECT_LE(run.max_force_step, 0.05);
  EXPECT_EQ(run.allocations, 0);
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
      link.PassInto(&servo, snap);
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

// Issue 33's third canonical case: a box's flat bottom face on a flat floor
// (testing/conformal_scenes.h), held by the corners of the face (server/face_contacts.h).
struct BoxOutcome {
  double worst_violation = 0.0;
  double lowest_corner = 1.0;  ///< the box's lowest bottom corner's height over the floor (m)
  double press_force = 0.0;    ///< mean F_z pressed and still (2–3 s)
  Eigen::Vector4d press_loads = Eigen::Vector4d::Zero();  ///< the four corners' loads at 3 s
  double push_force_min = 1e9, push_force_max = 0.0;      ///< F_z while pushed along x (3.5–5 s)
  /// Tilted (6–8 s): the largest |F_z − the corners' summed load|, and the largest load on a
  /// corner of the raised side while the box stands on its other edge.
  double worst_balance = 0.0, raised_load = 0.0;
  double tilted = 0.0;  ///< the box's largest turn from its start (rad)
  /// At the tilts' peaks (6 s and 8 s: the hand still), F_z and the box's turn (rad).
  double peak_force[2] = {0.0, 0.0}, peak_tilt[2] = {0.0, 0.0};
  double max_force_step = 0.0;
  long allocations = 0;     ///< in the servo's ticks from 3.5 s
  int held_steps = 0;       ///< device steps with the face pair held
  bool held_at_end = true;  ///< the face pair still held at the last step (lifted off: released)
  double end_force = 1.0;   ///< |F| at the last step
};

// 1 kHz device states, four servo ticks each, a global pass per device step. From 1 s the hand
// presses 2 mm down; from 3 s it pushes the box ±5 mm along x; from 5 s, still pressing, it
// tilts it about x, 12° each way (peaks at 6 s and 8 s); from 9 s it lifts it 3 mm off.
BoxOutcome DriveBox(bool faces, double seconds) {
  auto scene = ParseScene(testing::kBoxScene, "box.json");
  ServoOptions options;
  options.dof = 6;
  options.face_contacts = faces;
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  BoxOutcome out;
  int64_t now = 1'000'000'000;
  int pressed = 0;
  const int box = scene->BodyIndex("box");
  Eigen::Vector3d last_force = Eigen::Vector3d::Zero();
  const double tilt = 12.0 * std::numbers::pi / 180.0;
  for (int step = 1; step <= static_cast<int>(seconds * 1000); ++step) {
    const double t = 1e-3 * step;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (t > 1.0) p.z() = -2e-3 * std::min(1.0, t - 1.0);
    if (t > 3.0 && t <= 5.0) p.x() = 5e-3 * std::sin(std::numbers::pi * (t - 3.0));
    if (t > 9.0) p.z() = -2e-3 + 5e-3 * std::min(1.0, t - 9.0);  // lifted 3 mm off the floor
    const double angle =
        t > 5.0 && t <= 9.0 ? tilt * std::sin(std::numbers::pi * (t - 5.0) / 2.0) : 0.0;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()));
    const DeviceSample s = bench::HandSample(step, now, p, q);
    const long before = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += 250'000;
      out.worst_violation = std::max(out.worst_violation, r.violation);
    }
    if (t > 3.5) out.allocations += testing::AllocationCount() - before;
    servo.FillSnapshot(&snap);
    link.PassInto(&servo, snap);
    const bool held = servo.faces().pairs() > 0 && servo.faces().held(0);
    out.held_steps += held;
    out.held_at_end = held;
    const Eigen::Vector3d f(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
    out.max_force_step = std::max(out.max_force_step, (f - last_force).norm());
    last_force = f;
    const Eigen::Quaterniond turn(snap.q[box][3], snap.q[box][4], snap.q[box][5], snap.q[box][6]);
    const Eigen::Vector3d centre(snap.q[box][0], snap.q[box][1], snap.q[box][2]);
    const Eigen::Matrix3d R = turn.normalized().toRotationMatrix();
    for (double x : {-10e-3, 10e-3}) {
      for (double y : {-10e-3, 10e-3}) {
        out.lowest_corner =
            std::min(out.lowest_corner, (centre + R * Eigen::Vector3d(x, y, 0)).z());
      }
    }
    out.tilted =
        std::max(out.tilted, turn.normalized().angularDistance(Eigen::Quaterniond::Identity()));
    if (t > 2.0 && t <= 3.0) {
      out.press_force += f.z();
      ++pressed;
    }
    // The corners' loads: the bottom face's four (f is the floor, the scene's first surface:
    // the face's corners are g's, FaceContacts' 4–7).
    Eigen::Vector4d loads = Eigen::Vector4d::Zero();
    if (held) {
      for (int i = 0; i < 4; ++i) loads[i] = servo.FaceLoad(0, 4 + i);
    }
    if (step == 3000) out.press_loads = loads;
    if (step == 6000 || step == 8000) {
      out.peak_force[step / 2000 - 3] = f.z();
      out.peak_tilt[step / 2000 - 3] =
          turn.normalized().angularDistance(Eigen::Quaterniond::Identity());
    }
    if (t > 3.5 && t <= 5.0) {
      out.push_force_min = std::min(out.push_force_min, f.z());
      out.push_force_max = std::max(out.push_force_max, f.z());
    }
    if (t > 6.0 && held) {
      // Frictionless, massless at rest: the floor's push on the corners is the hand's on the box.
      double all = 0.0;
      for (int i = 0; i < FaceContacts::kCorners; ++i) all += servo.FaceLoad(0, i);
      out.worst_balance = std::max(out.worst_balance, std::abs(f.z() - all));
      // Standing on one edge (tilted beyond 3°): the corners of the raised edge carry nothing.
      // The bottom face's corners in FlatQuad order: (u, v) = (0, 0), (1, 0), (1, 1), (0, 1),
      // at y = −10, +10, +10, −10 mm (edge_u along +y).
      if (std::abs(angle) > 3.0 * std::numbers::pi / 180.0) {
        const bool raised_plus_y = angle > 0.0;  // turned about +x: +y rises
        for (int i = 0; i < 4; ++i) {
          const bool plus_y = i == 1 || i == 2;
          if (plus_y == raised_plus_y) out.raised_load = std::max(out.raised_load, loads[i]);
        }
      }
    }
    if (faces && step % 1000 == 0) {
      std::printf("  %.1f s: corner loads %.4f %.4f %.4f %.4f N, F_z %.4f N, tilt %.2f deg\n", t,
                  loads[0], loads[1], loads[2], loads[3], f.z(), angle * 180 / std::numbers::pi);
    }
  }
  if (pressed > 0) out.press_force /= pressed;
  out.end_force = last_force.norm();
  std::printf(
      "%s: worst violation %.1e m, lowest corner %.2e m, pressing %.4f N (corners %.4f %.4f %.4f "
      "%.4f N), pushed %.4f to %.4f N, tilted %.1f deg, |F_z - corner loads| %.1e N, raised "
      "corners' load %.1e N, largest force step %.4f N, %ld allocations from 3.5 s, held %d of "
      "%d device steps\n",
      faces ? "face contacts" : "as slots", out.worst_violation, out.lowest_corner, out.press_force,
      out.press_loads[0], out.press_loads[1], out.press_loads[2], out.press_loads[3],
      out.push_force_min, out.push_force_max, out.tilted * 180 / std::numbers::pi,
      out.worst_balance, out.raised_load, out.max_force_step, out.allocations, out.held_steps,
      static_cast<int>(seconds * 1000));
  return out;
}

// The box tilted by the hand stands on one edge of its bottom face: its turn θ and the hand's
// F_z at rest solve the statics of the two springs (the coupling k at the centre, 5 mm over the
// face and 10 mm in from the edge, its target 2 mm under the resting centre; the rotational
// coupling's energy k_r (1 − cos(θ_t − θ)), docs/server.md) about that edge, frictionless:
// d/dθ [½ k (h(θ) − z_t)² + k_r (1 − cos(θ_t − θ))] = 0, h(θ) = 10 sin θ + 5 cos θ mm.
std::pair<double, double> TiltedStatics(double k, double k_r, double theta_t, double z_t) {
  auto h = [](double t) { return 10e-3 * std::sin(t) + 5e-3 * std::cos(t); };
  auto dh = [](double t) { return 10e-3 * std::cos(t) - 5e-3 * std::sin(t); };
  auto dE = [&](double t) { return k * (h(t) - z_t) * dh(t) - k_r * std::sin(theta_t - t); };
  double lo = 0.0, hi = theta_t;  // dE(0) < 0 < dE(θ_t)
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (dE(mid) < 0.0 ? lo : hi) = mid;
  }
  return {lo, k * (h(lo) - z_t)};
}

TEST(ConformalTest, ABoxOnAFloorIsHeldByItsFacesCornersPressedPushedAndTilted) {
  const BoxOutcome run = DriveBox(true, 10.5);
  const double k = 300.0, gap = 0.05e-3;
  EXPECT_LE(run.worst_violation, 1e-6);
  EXPECT_GE(run.lowest_corner, -1e-6);  // no corner through the floor
  // Pressed 2 mm, it moves the gap: k (2 mm − gap), shared by the four corners.
  EXPECT_NEAR(run.press_force, k * (2e-3 - gap), 1e-4);
  EXPECT_NEAR(run.press_loads.sum(), k * (2e-3 - gap), 1e-4);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(run.press_loads[i], k * (2e-3 - gap) / 4, 1e-3);
  EXPECT_GT(run.push_force_min, k * (2e-3 - gap) - 1e-4);  // still pressed while pushed
  EXPECT_LT(run.push_force_max, k * (2e-3 - gap) + 1e-4);
  const auto [theta, force] = TiltedStatics(k, 0.2, 12.0 * std::numbers::pi / 180, 3.05e-3);
  std::printf("tilted statics: %.4f deg, F_z %.5f N\n", theta * 180 / std::numbers::pi, force);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(run.peak_tilt[i], theta, 1e-3);
    EXPECT_NEAR(run.peak_force[i], force, 0.005 * force);
  }
  EXPECT_LT(run.worst_balance, 0.01);  // (the coupling's damping while it turns)
  EXPECT_LT(run.raised_load, 1e-6);    // standing on one edge: the other carries nothing
  EXPECT_LE(run.max_force_step, 0.5);  // the rate limit: 500 N/s over a 1 ms device step
  EXPECT_EQ(run.allocations, 0);
  EXPECT_FALSE(run.held_at_end);   // lifted off: released
  EXPECT_LT(run.end_force, 1e-3);  // and nothing felt
}

TEST(ConformalTest, WithoutFaceContactsTheFloorDoesNotHoldTheBox) {
  // The pair as extremal slots: the continuum is no contact the stage finds, nothing resists the
  // press, and the face goes through the floor (what the corners above are for).
  const BoxOutcome run = DriveBox(false, 3.0);
  EXPECT_LT(std::abs(run.press_force), 0.1);
  EXPECT_LT(run.lowest_corner, -1e-3);
  EXPECT_EQ(run.held_steps, 0);
}

}  // namespace
}  // namespace tangent::server
