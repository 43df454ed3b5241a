// Issue 33's first canonical conformal case: a rod lying in a cylindrical groove of 1 % larger
// radius (a line contact: every point along the bottom line is an extremal pair), pressed into
// it by the hand and slid along it, through the servo and the global stage. With line contacts
// (ServoOptions::line_contacts) the pair is held by three sections across the line and the hand
// feels the pressing force; as one point (the default) the continuum is not a contact the stage
// can take, and the rod is pushed through the groove.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "server/global_link.h"
#include "server/scene.h"
#include "server/servo.h"
#include "testing/alloc_counter.h"

namespace tangent::server {
namespace {

// The groove: a cylinder of radius 5.05 mm facing its axis, 40 mm along x; the rod: radius
// 5 mm, 20 mm long, lying on the groove's bottom line (0.05 mm below the groove's axis).
const char* kGroove = R"JSON({
  "name": "rod in a groove",
  "length_unit": "mm",
  "bodies": [
    {"name": "block", "fixed": true},
    {"name": "rod", "position": [0, 0, -0.05], "mass": 0.01, "inertia": [8e-07, 8e-07, 1e-07]}
  ],
  "surfaces": [
    {"name": "groove", "body": "block", "type": "cylinder", "radius": 5.05, "height": 40,
     "position": [-20, 0, 0], "quaternion": [0.7071067811865476, 0, 0.7071067811865476, 0],
     "reverse_normal": true},
    {"name": "rod_side", "body": "rod", "type": "cylinder", "radius": 5, "height": 20,
     "position": [-10, 0, 0], "quaternion": [0.7071067811865476, 0, 0.7071067811865476, 0]}
  ],
  "contacts": [{"a": "groove", "b": "rod_side", "kind": "unilateral", "max_contacts": 2}],
  "grasp": {"body": "rod", "point": [0, 0, 0], "hold_orientation": 0.01},
  "device": {"id": 1, "scale": 1.0, "stiffness": 300, "damping": 1.0, "max_force": 3.3,
             "max_force_rate": 500, "ramp_time": 1.0},
  "offset": {"tolerance": 0.02, "margin": 0.25}
})JSON";

struct Outcome {
  double worst_violation = 0.0;  ///< from 1.5 s (the ramp up and the first press done)
  double press_force = 0.0;      ///< mean hand force along z over 2–3 s (pressing, still)
  double slide_force_min = 1e9, slide_force_max = 0.0;  ///< |F_z| while sliding (3.5–5 s)
  double line_force = 0.0;                              ///< the line's reported load at 3 s (N)
  int line_ticks = 0;                                   ///< device steps with the pair in line mode
  long slide_allocations = 0;  ///< heap allocations in the servo's ticks while sliding
};

// The hand presses 2 mm down from 1 s (0.6 N at 300 N/m), then from 3 s slides ±5 mm along the
// groove; 1 kHz device states, four servo ticks each, a global pass per device step.
Outcome Drive(bool lines, double seconds) {
  auto scene = ParseScene(kGroove, "groove.json");
  ServoOptions options;
  options.line_contacts = lines;
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  TickResult r;
  Snapshot snap;
  Outcome out;
  int64_t now = 1'000'000'000;
  int pressed = 0;
  for (int k = 1; k <= static_cast<int>(seconds * 1000); ++k) {
    const double t = 1e-3 * k;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    if (t > 1.0) p.z() = -2e-3 * std::min(1.0, t - 1.0);
    if (t > 3.0) p.x() = 5e-3 * std::sin(1.5 * (t - 3.0));
    DeviceSample s;
    s.seq = k;
    s.utime = now / 1000;
    s.received_ns = now;
    for (int i = 0; i < 3; ++i) s.position[i] = p[i];
    const bool sliding = t > 3.5;
    const long before = testing::AllocationCount();
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += 250'000;
      if (t > 1.5) out.worst_violation = std::max(out.worst_violation, r.violation);
    }
    if (sliding) out.slide_allocations += testing::AllocationCount() - before;
    servo.FillSnapshot(&snap);
    link.Pass(snap, [&](const ContactEventMsg& m) { servo.Apply(m); });
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
      "line mode %d of %d device steps, %ld allocations while sliding\n",
      lines ? "line contacts" : "one point", out.worst_violation, out.press_force, out.line_force,
      out.slide_force_min, out.slide_force_max, out.line_ticks, static_cast<int>(seconds * 1000),
      out.slide_allocations);
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
}

TEST(ConformalTest, AsOnePointTheGrooveDoesNotHoldTheRod) {
  // The default model: the continuum is no contact the global stage takes, so nothing resists
  // the press and the hand feels nothing (what the line model above is for).
  const Outcome run = Drive(false, 3.0);
  EXPECT_LT(std::abs(run.press_force), 0.1);
  EXPECT_EQ(run.line_ticks, 0);
}

}  // namespace
}  // namespace tangent::server
