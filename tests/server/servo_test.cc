// The servo loop on the example scenes, without threads: exact contacts at rest, bounded
// violation while dragged, contact events applied through slots, the coupling's force limits,
// the device timeout, 6-DOF torque, and no allocation in a tick.

#include "server/servo.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>

#include <Eigen/Geometry>

#include "server/global_link.h"
#include "testing/alloc_counter.h"
#include "testing/drag_path.h"
#include "testing/idle_parts.h"

namespace tangent::server {
namespace {

constexpr double mm = 1e-3;

std::unique_ptr<Scene> Load(const char* name) {
  return LoadScene(std::string(TANGENT_SCENES_DIR) + "/" + name + ".json");
}

DeviceSample Sample(int64_t seq, const Eigen::Vector3d& p, int64_t now_ns) {
  DeviceSample s;
  s.seq = seq;
  s.utime = now_ns / 1000;
  s.received_ns = now_ns;
  for (int i = 0; i < 3; ++i) s.position[i] = p[i];
  return s;
}

TEST(ServoTest, PaperclipsRestExactlyAndStayWithinMicrometresWhileDragged) {
  auto scene = Load("paperclips");
  ServoLoop servo(*scene, ServoOptions{});
  EXPECT_EQ(servo.active_contacts(), 2);  // both hooks, found by the global stage at load
  GlobalLink link(servo);
  Snapshot snap;
  TickResult r;
  int64_t now = 1'000'000'000;
  // At rest: the hand at the grasp point.
  double rest = 0.0;
  for (int k = 1; k <= 200; ++k) {
    const DeviceSample s = Sample(k, Eigen::Vector3d::Zero(), now);
    servo.Tick(&s, now, &r);
    now += 250'000;
    if (k > 20) rest = std::max(rest, r.violation);
  }
  EXPECT_LE(rest, 1e-10);
  // Drag: lift 6 mm and circle (the phantom's "drag" path, without device dynamics), 1 kHz device
  // states, 4 servo ticks each, a global pass every 4 ticks.
  double worst = 0.0, max_force = 0.0, force_lifted = 0.0;
  int events_applied = 0, budget_ticks = 0, ticks = 0;
  long allocations = 0;
  int64_t seq = 1000;
  const ServoLoop::TrackingCounts tracking_before = servo.Tracking();
  int64_t tracked = 0, solves = 0, lost = 0;
  for (int k = 0; k < 6000; ++k) {
    const double t = 1e-3 * k;
    const DeviceSample s = bench::DragSample(++seq, t, now);
    for (int tick = 0; tick < 4; ++tick) {
      const long before = tangent::testing::AllocationCount();
      servo.Tick(&s, now, &r);
      allocations += tangent::testing::AllocationCount() - before;
      now += 250'000;
      worst = std::max(worst, r.violation);
      budget_ticks += r.iterations >= ServoOptions{}.max_iterations;
      tracked += r.tracked;
      solves += r.solves;
      lost += r.lost;
      ++ticks;
      if (r.answered) {
        const double f =
            Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]).norm();
        max_force = std::max(max_force, f);
        if (std::abs(t - 2.0) < 1e-9) force_lifted = f;
      }
    }
    servo.FillSnapshot(&snap);
    link.Pass(snap, [&](const ContactEventMsg& m) {
      const long before = tangent::testing::AllocationCount();
      events_applied += servo.Apply(m);
      allocations += tangent::testing::AllocationCount() - before;
    });
    servo.AdoptClearances(link.clearances());
  }
  std::printf(
      "paperclip servo: rest violation %.1e, drag worst violation %.1e, force when lifted %.2f N, "
      "max %.2f N, contacts now %d, events applied %d, allocations %ld, ticks at the iteration "
      "budget %d of %d\n",
      rest, worst, force_lifted, max_force, servo.active_contacts(), events_applied, allocations,
      budget_ticks, ticks);
  EXPECT_LE(worst, 1e-9);  // (issue 6 asks 1e-6)
  // The hooks stay loaded through the drag: their contacts must not cycle through the budget
  // (8 % of ticks did while the active set came from the current point alone).
  EXPECT_LE(budget_ticks, ticks / 200);
  EXPECT_GT(force_lifted, 0.3);  // the hooks hold the chain back: the hand feels the pull
  EXPECT_LE(max_force, scene->device.max_force + 1e-12);
  EXPECT_EQ(allocations, 0);
  // The contacts are followed by contact/'s tracker (predict with u_q, correct): its states
  // reach every tick's result, the totals agree, most evaluations need no full solve, and each
  // `lost` step was answered by a full solve (counted among the solves).
  const ServoLoop::TrackingCounts tracking_after = servo.Tracking();
  EXPECT_EQ(tracked, tracking_after.tracked - tracking_before.tracked);
  EXPECT_EQ(solves, tracking_after.solves - tracking_before.solves);
  EXPECT_EQ(lost, tracking_after.lost - tracking_before.lost);
  EXPECT_GT(tracked, 10 * solves);
  EXPECT_LE(lost, solves);
  std::printf("contact evaluations while dragged: %lld tracked, %lld solved, %lld lost\n",
              static_cast<long long>(tracked), static_cast<long long>(solves),
              static_cast<long long>(lost));
  // Every tracked contact is a non-penetration contact at β ≥ −1e-6.
  servo.FillSnapshot(&snap);
  for (int k = 0; k < snap.num_contacts; ++k) EXPECT_GE(snap.contacts[k].beta, -1e-6);
}

TEST(ServoTest, ThePaperclipChainPulledFromRestHolds) {
  // The hooks at rest touch unloaded (β = 0, λ = 0). A session opens with the hand 4 mm off the
  // grasp point in a direction within 45° of the chain's axis, at device periods and servo ticks
  // as jittered as tangentd's (ticks 10 µs to 0.45 ms apart, the first after 10 µs to 2 ms).
  // Every variant must keep both hooks and resist: measured before the first solve estimated
  // the touching contacts' multipliers, 4 to 8 in 100 such starts came apart (a first Newton
  // step turned clip 1 17° into the other wire), one of them on CI (server_adversary).
  auto scene = Load("paperclips");
  int apart = 0, budget_ticks = 0, ticks = 0;
  double worst = 0.0, weakest = 1e300;
  long allocations = 0;
  for (int run = 0; run < 40; ++run) {
    std::mt19937 rng(static_cast<unsigned>(run));
    ServoLoop servo(*scene, ServoOptions{});
    GlobalLink link(servo);
    Snapshot snap;
    TickResult r;
    int64_t now = 1'000'000'000, seq = 0;
    std::uniform_real_distribution<double> jitter(1e-5, 4.5e-4), first(1e-5, 2e-3), unit(0.0, 1.0);
    const double theta = unit(rng) * std::numbers::pi / 4, phi = 2 * std::numbers::pi * unit(rng);
    const Eigen::Vector3d hand = 4 * mm *
                                 Eigen::Vector3d(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                 std::sin(theta) * std::sin(phi));
    const int idle = std::uniform_int_distribution<int>(0, 400)(rng);
    for (int k = 0; k < idle; ++k) {
      servo.Tick(nullptr, now, &r);
      now += 250'000;
    }
    double force = 0.0;
    for (int k = 0; k < 500; ++k) {
      DeviceSample s = Sample(++seq, hand, now);
      const int per = std::uniform_int_distribution<int>(3, 6)(rng);
      for (int tick = 0; tick < per; ++tick) {
        const long before = tangent::testing::AllocationCount();
        servo.Tick(&s, now, &r);
        allocations += tangent::testing::AllocationCount() - before;
        now += static_cast<int64_t>(1e9 * (k == 0 && tick == 0 ? first(rng) : jitter(rng)));
        worst = std::max(worst, r.violation);
        budget_ticks += r.iterations >= ServoOptions{}.max_iterations;
        ++ticks;
        if (r.answered) {
          force = Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]).norm();
        }
      }
      if (k % 4 == 3) {
        servo.FillSnapshot(&snap);
        link.PassInto(&servo, snap);
      }
    }
    // 0.5 s into the 1 s ramp, a chain that holds pulls back with about half of k × 4 mm.
    const bool held = servo.active_contacts() >= 2 && force > 0.2;
    apart += !held;
    weakest = std::min(weakest, force);
    if (!held) {
      std::printf("run %d (hand %.2f %.2f %.2f mm, %d idle ticks): contacts %d, |F| %.3f N\n", run,
                  hand[0] / mm, hand[1] / mm, hand[2] / mm, idle, servo.active_contacts(), force);
    }
  }
  std::printf(
      "chain pulled from rest, 40 starts: %d apart, weakest final pull %.3f N, worst violation "
      "%.1e, ticks at the iteration budget %d of %d, allocations %ld\n",
      apart, weakest, worst, budget_ticks, ticks, allocations);
  EXPECT_EQ(apart, 0);
  EXPECT_LE(worst, 1e-9);
  EXPECT_EQ(allocations, 0);
}

TEST(ServoTest, ARemovalFreesOnlyTheContactItNames) {
  auto scene = Load("paperclips");
  ServoLoop servo(*scene, ServoOptions{});
  ASSERT_EQ(servo.active_contacts(), 2);
  Snapshot snap;
  servo.FillSnapshot(&snap);
  const TrackedContact held = snap.contacts[0];
  ContactEventMsg m;
  m.added = 0;
  m.surface_a = held.surface_a;
  m.surface_b = held.surface_b;
  // Parameters a quarter of the domain away: another contact, already gone. Refused.
  for (int i = 0; i < 4; ++i) m.u[i] = held.u[i];
  m.u[2] = m.u[2] > 0.5 ? m.u[2] - 0.25 : m.u[2] + 0.25;
  EXPECT_FALSE(servo.Apply(m));
  EXPECT_EQ(servo.active_contacts(), 2);
  // Its own parameters (moved a little since the global stage saw them): freed.
  for (int i = 0; i < 4; ++i) m.u[i] = held.u[i] + 1e-3;
  EXPECT_TRUE(servo.Apply(m));
  EXPECT_EQ(servo.active_contacts(), 1);
}

TEST(ServoTest, DeviceTimeoutRampsTheForceToZeroAndHoldsTheScene) {
  auto scene = Load("paperclips");
  ServoLoop servo(*scene, ServoOptions{});
  TickResult r;
  int64_t now = 1'000'000'000;
  DeviceSample s;
  int64_t seq = 0;
  for (int k = 0; k < 3000; ++k) {  // ramp up, then pull 5 mm
    s = Sample(++seq, Eigen::Vector3d(0, 5 * mm * std::min(1.0, k / 1000.0), 0), now);
    servo.Tick(&s, now, &r);
    now += 1'000'000;
  }
  const double pulled =
      Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]).norm();
  EXPECT_GT(pulled, 0.5);
  const Eigen::VectorXd held = servo.q();
  // The device goes silent: the same (stale) sample from now on. Until the timeout nothing is
  // sent; then one timeout wrench per device period, echoing the last state answered, ramping
  // down continuously, until a last one at zero.
  double previous = pulled;
  int timeout_wrenches = 0, zero_wrenches = 0;
  for (int k = 0; k < 2000; ++k) {
    servo.Tick(&s, now, &r);
    now += 1'000'000;
    EXPECT_EQ(r.timed_out, k >= 100) << k;  // timeout 0.1 s
    EXPECT_EQ(r.answered, k >= 100 && zero_wrenches == 0) << k;
    if (!r.answered) continue;
    ++timeout_wrenches;
    EXPECT_EQ(r.wrench.state, kTimeout);
    EXPECT_EQ(r.wrench.seq, s.seq);
    const double f =
        Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]).norm();
    EXPECT_LE(f, previous + 1e-12);
    EXPECT_LE(previous - f, scene->device.max_force_rate * 1e-3 + 1e-12);
    previous = f;
    zero_wrenches += f == 0.0;
  }
  EXPECT_EQ(zero_wrenches, 1);
  EXPECT_GE(timeout_wrenches, 900);            // the 1 s ramp, one per millisecond
  EXPECT_LT((servo.q() - held).norm(), 1e-6);  // the scene holds
  // A new device state after the silence: answered, ramping up from zero.
  s = Sample(++seq, Eigen::Vector3d(0, 5 * mm, 0), now);
  servo.Tick(&s, now, &r);
  ASSERT_TRUE(r.answered);
  EXPECT_EQ(r.wrench.state, 1);  // ramping
  const double after =
      Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]).norm();
  EXPECT_LT(after, 0.05 * pulled);
}

TEST(ServoTest, SixDofTorqueRestoresTheStylusTowardThePart) {
  auto scene = Load("fourbar_point");
  ServoOptions o;
  o.dof = 6;
  ServoLoop servo(*scene, o);
  TickResult r;
  int64_t now = 1'000'000'000;
  const double theta = 0.1;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()));
  for (int k = 1; k <= 3000; ++k) {
    DeviceSample s = Sample(k, Eigen::Vector3d::Zero(), now);
    const double f = std::min(1.0, k / 1000.0);
    const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(f, turn);
    s.orientation[0] = q.w();
    s.orientation[1] = q.x();
    s.orientation[2] = q.y();
    s.orientation[3] = q.z();
    servo.Tick(&s, now, &r);
    now += 1'000'000;
  }
  // The coupler cannot turn about x (its joints forbid it): the hand feels a torque back, about
  // −x, at most the rotational stiffness times the angle.
  std::printf("6-DOF: torque %.4f %.4f %.4f N m for a %.2f rad twist (k_rot %.3f N m/rad)\n",
              r.wrench.torque[0], r.wrench.torque[1], r.wrench.torque[2], theta,
              scene->grasp.rotational_stiffness);
  EXPECT_LT(r.wrench.torque[0], -0.1 * scene->grasp.rotational_stiffness * theta);
  EXPECT_LE(std::abs(r.wrench.torque[0]), 1.05 * scene->grasp.rotational_stiffness * theta);
  // 3-DOF mode sends no torque.
  auto scene3 = Load("fourbar_point");
  ServoLoop servo3(*scene3, ServoOptions{});
  DeviceSample s = Sample(1, Eigen::Vector3d::Zero(), now);
  servo3.Tick(&s, now, &r);
  EXPECT_EQ(r.wrench.torque[0], 0.0);
}

TEST(ServoTest, FloatingGraspKeepsTheFingerOnThePad) {
  auto scene = Load("fourbar_floating");
  ServoLoop servo(*scene, ServoOptions{});
  TickResult r;
  int64_t now = 1'000'000'000;
  double worst = 0.0;
  for (int k = 1; k <= 2000; ++k) {
    const double a = 2 * std::numbers::pi * k / 2000.0;
    const DeviceSample s =
        Sample(k, 10 * mm * Eigen::Vector3d(0, std::sin(a), 1 - std::cos(a)), now);
    servo.Tick(&s, now, &r);
    now += 1'000'000;
    if (k > 5) worst = std::max(worst, r.violation);
  }
  std::printf("floating grasp servo: worst violation %.1e\n", worst);
  EXPECT_LE(worst, 1e-6);
}

TEST(ServoTest, BadOptionsAreRejected) {
  auto scene = Load("fourbar_point");
  ServoOptions o;
  o.dof = 4;
  try {
    ServoLoop servo(*scene, o);
    FAIL() << "dof 4 accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("dof must be 3 or 6, got 4"), std::string::npos);
  }
}

// Model only what a scene needs: the paperclips with seventeen more clips declared but in no
// contact pair, joint, grasp or objective. The idle clips are held fixed (no coordinates), get no
// offset mesh, and the drag computes exactly what the three-clip scene computes: the same
// wrenches, bit for bit, through the same events. (What they cost in time, same run:
// bench/servo_profile --idle-parts.)
TEST(ServoTest, IdlePartsAreNotModelled) {
  const auto three = Load("paperclips");
  const auto twenty = ParseScene(tangent::testing::PaperclipsWithIdleClips(TANGENT_SCENES_DIR, 17),
                                 "paperclips + 17 idle clips", TANGENT_SCENES_DIR);
  ASSERT_EQ(twenty->mechanism.num_bodies(), 20);
  ServoLoop a(*three, ServoOptions{}), b(*twenty, ServoOptions{});
  EXPECT_EQ(b.problem().mechanism().num_coordinates(), a.problem().mechanism().num_coordinates());
  EXPECT_EQ(b.problem().mechanism().num_coordinates(), 14);  // the two free clips
  EXPECT_EQ(b.problem().equalities().size(), a.problem().equalities().size());
  EXPECT_EQ(b.problem().inequalities().size(), a.problem().inequalities().size());
  for (size_t k = 3; k < twenty->surfaces.size(); ++k) {
    EXPECT_FALSE(twenty->surfaces[k].watched);
    EXPECT_TRUE(twenty->surfaces[k].mesh.vertices.empty()) << k;
  }
  GlobalLink link_a(a), link_b(b);
  Snapshot snap;
  TickResult ra, rb;
  int64_t now = 1'000'000'000, differences = 0, events = 0;
  for (int k = 0; k < 1500; ++k) {
    const DeviceSample s = bench::DragSample(k + 1, 4e-3 * k, now);
    for (int tick = 0; tick < 4; ++tick) {
      a.Tick(&s, now, &ra);
      b.Tick(&s, now, &rb);
      now += 250'000;
      for (int i = 0; i < 3; ++i) differences += ra.wrench.force[i] != rb.wrench.force[i];
    }
    a.FillSnapshot(&snap);
    link_a.PassInto(&a, snap, [&](const ContactEventMsg&, bool applied) { events += applied; });
    b.FillSnapshot(&snap);
    link_b.PassInto(&b, snap);
  }
  EXPECT_EQ(differences, 0);
  EXPECT_GT(events, 0);  // the drag made and broke contacts on the way
}

// Two bodies of two spheres each with contact declared between the bodies: "ground" (fixed;
// faces g1, g2: surfaces 0, 1) and "ball" (b1, b2: 2, 3; b1 resting 0.05 mm off g1, sideways
// so the contact is on both spheres' equators). `extra`: more faces on the ground.
std::string TwoBodyScene(int max_contacts, const std::string& extra = "") {
  return R"({"bodies": [{"name": "ground", "fixed": true},
                        {"name": "ball", "mass": 0.01, "position": [0.01505, 0, 0]}],
    "surfaces": [{"name": "g1", "body": "ground", "type": "sphere", "radius": 0.01},
                 {"name": "g2", "body": "ground", "type": "sphere", "radius": 0.01,
                  "center": [0, 0, 0.1]},
                 {"name": "b1", "body": "ball", "type": "sphere", "radius": 0.005},
                 {"name": "b2", "body": "ball", "type": "sphere", "radius": 0.005,
                  "center": [0, 0, 0.04]})" +
         extra + R"(],
    "contacts": [{"bodies": ["ground", "ball"], "max_contacts": )" +
         std::to_string(max_contacts) + R"(}],
    "grasp": {"body": "ball"}})";
}

TEST(ServoTest, ABodyPairsContactsTakeSlotsFromOnePoolMovedToTheirFacePairs) {
  const auto scene = ParseScene(TwoBodyScene(3), "bodies.json");
  ASSERT_EQ(scene->body_pairs.size(), 1u);
  EXPECT_TRUE(scene->pairs.empty());
  for (const SceneSurface& sf : scene->surfaces) EXPECT_TRUE(sf.watched) << sf.name;
  ServoLoop servo(*scene, ServoOptions{});
  // The pool's rows are the pair's slots, not its face pairs: three for 2 x 2 faces, and three
  // for 4 x 2.
  EXPECT_EQ(servo.problem().inequalities().size(), 3u);
  const auto wider = ParseScene(
      TwoBodyScene(3, R"(, {"name": "g3", "body": "ground", "type": "sphere", "radius": 0.01,
                     "center": [0, 0.1, 0]}, {"name": "g4", "body": "ground", "type": "sphere",
                     "radius": 0.01, "center": [0, -0.1, 0]})"),
      "wider.json");
  EXPECT_EQ(ServoLoop(*wider, ServoOptions{}).problem().inequalities().size(), 3u);
  // The cold pass found b1 on g1 (surfaces 0 and 2) and took a slot for it.
  ASSERT_EQ(servo.active_contacts(), 1);
  Snapshot snap;
  servo.FillSnapshot(&snap);
  EXPECT_EQ(snap.contacts[0].surface_a, 0);
  EXPECT_EQ(snap.contacts[0].surface_b, 2);
  EXPECT_EQ(snap.contacts[0].body_a, 0);
  EXPECT_EQ(snap.contacts[0].body_b, 1);
  EXPECT_NEAR(snap.contacts[0].beta, 0.05e-3, 1e-12);  // nothing presses it closer
  // Events on other face pairs of the bodies take the pool's other slots, in the pair's order.
  auto event = [](int added, int a, int b, double u0) {
    ContactEventMsg m;
    m.added = added;
    m.surface_a = a;
    m.surface_b = b;
    m.u[0] = u0;
    m.u[1] = 0.3;
    m.u[2] = 0.6;
    m.u[3] = 0.7;
    return m;
  };
  EXPECT_TRUE(servo.Apply(event(1, 3, 1, 0.2)));  // b2 on g2, named in either order
  EXPECT_TRUE(servo.Apply(event(1, 0, 3, 0.4)));  // b2 on g1
  EXPECT_EQ(servo.active_contacts(), 3);
  EXPECT_FALSE(servo.Apply(event(1, 1, 2, 0.4)));  // b1 on g2: the pool is used up
  EXPECT_FALSE(servo.Apply(event(1, 0, 1, 0.4)));  // g1 on g2: one body, no pair
  servo.FillSnapshot(&snap);
  ASSERT_EQ(snap.num_contacts, 3);
  EXPECT_EQ(snap.contacts[1].surface_a, 1);
  EXPECT_EQ(snap.contacts[1].surface_b, 3);
  EXPECT_EQ(snap.contacts[1].u[0], 0.2);  // the pair's order, as the event gave it
  EXPECT_EQ(snap.contacts[1].u[3], 0.7);
  // A removal frees the slot of the contact it names, on its face pair only.
  EXPECT_FALSE(servo.Apply(event(0, 1, 2, 0.2)));
  EXPECT_TRUE(servo.Apply(event(0, 1, 3, 0.2)));
  EXPECT_EQ(servo.active_contacts(), 2);
  EXPECT_TRUE(servo.Apply(event(1, 1, 2, 0.4)));  // and that slot moves on to b1 on g2
  servo.FillSnapshot(&snap);
  EXPECT_EQ(snap.contacts[1].surface_a, 1);
  EXPECT_EQ(snap.contacts[1].surface_b, 2);
  // Ticks with the moved slots allocate nothing.
  DeviceSample d;
  d.orientation[0] = 1.0;
  TickResult r;
  int64_t now = 1'000'000'000;
  const long before = tangent::testing::AllocationCount();
  for (int k = 0; k < 50; ++k) {
    d.seq = k + 1;
    d.received_ns = now;
    servo.Tick(&d, now, &r);
    now += 250'000;
    EXPECT_LE(r.violation, 1e-10);
  }
  EXPECT_EQ(tangent::testing::AllocationCount() - before, 0);
}

}  // namespace
}  // namespace tangent::server
