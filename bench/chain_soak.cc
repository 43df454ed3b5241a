// The soak's paperclip drag offline (docs/reliability.md, "Soak"): the servo, the simulated
// device with its driver watchdog and the global stage stepped in one thread along the looped
// "drag" trajectory, deterministic. Prints, per simulated second: contacts, mean |F| at the hand,
// events, the worst violation and the ticks whose solve used its whole iteration budget or
// stopped at its motion bound unconverged (stalled); and
// when the chain comes apart (the force at the hand stays below 0.02 N for a whole
// circle while the drag pulls) or is held only by an unresolved penetration (a tick's constraint
// violation above issue 33's 1e-6 m: the solve jammed, as with the step reach on from 140 s; or
// a contact the global stage adds deeper than that: the rows missed it; or the wires' true gap,
// from their centre lines (testing/tube_gap.h, every 50 ms of the drag), below −1e-6 m: the
// wires crossed, whatever the rows read; or the solve stalled in more than half the ticks of a
// second: the chain no longer follows the hand, each tick's solve ending where it started,
// whatever its violation). Exit status 1 for either. At the end: the least true gap, and how
// many of the true-gap checks found the wires crossed.
//
//   ./build/bench/chain_soak [--seconds 150] [--from 0]   (print seconds from)
//                            [--trace-from T --trace-to T]  (every device step's contacts)
//                            [--points] [--reach]  (ServoOptions::line_contacts off,
//                                                    step_reach on)
//                            [--dip 1e-7]  (LineContactOptions::dip, m)
//                            [--normal-step]  (ServoOptions::bounded_normal_step)
//                            [--floor F]  (ServoOptions::indefinite_floor)
//                            [--iterations N]  (ServoOptions::max_iterations, default 10)
//                            [--truth-every 50]  (ms between true-gap checks; 0: none)
//                            [--pass-every 4]  (ms between global passes; tangentd's stage
//                                               thread passes about every 1.1 ms)
//                            [--jitter SEED]  (as a real-time run's: each tick ±20 % of its
//                                              250 µs, each pass skipped with probability 0.2)
//                            [--max-part-speed 0.2]  (ServoOptions::max_part_speed, m/s)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "server/global_link.h"
#include "server/phantom.h"
#include "server/scene.h"
#include "server/servo.h"
#include "testing/drag_path.h"
#include "testing/tube_gap.h"

using namespace tangent::server;

namespace {
// Issue 33's bar for every tick of a conformal case.
constexpr double kHeldViolation = 1e-6;
}  // namespace

int main(int argc, char** argv) {
  double seconds = 150.0, from = 0.0, trace_from = 1e9, trace_to = -1.0;
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--trace-from")) trace_from = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--trace-to")) trace_to = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--from")) from = std::atof(argv[i + 1]);
  }
  const auto scene = LoadScene(std::string(TANGENT_SCENES_DIR) + "/paperclips.json");
  ServoOptions options;
  int truth_every = 50;  // device steps (ms) between ground-truth gap checks; 0: none
  int pass_every = 4;    // device steps (ms) between global passes
  int jitter = 0;        // seed of the tick and pass jitter; 0: none
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--points")) options.line_contacts = false;
    if (!std::strcmp(argv[i], "--dip") && i + 1 < argc) options.line.dip = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--reach")) options.step_reach = true;
    if (!std::strcmp(argv[i], "--normal-step")) options.bounded_normal_step = true;
    if (!std::strcmp(argv[i], "--floor") && i + 1 < argc)
      options.indefinite_floor = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--truth-every") && i + 1 < argc)
      truth_every = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--jitter") && i + 1 < argc) jitter = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--max-part-speed") && i + 1 < argc)
      options.max_part_speed = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--pass-every") && i + 1 < argc)
      pass_every = std::max(1, std::atoi(argv[i + 1]));
    if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc)
      options.max_iterations = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--enter") && i + 1 < argc)
      options.line.enter = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--leave") && i + 1 < argc)
      options.line.leave = std::atof(argv[i + 1]);
  }
  ServoLoop servo(*scene, options);
  GlobalLink link(servo);
  {
    const auto t0 = std::chrono::steady_clock::now();
    const int built = link.Prepare();  // (as tangentd does before it serves)
    std::fprintf(
        stderr, "chain_soak: %d clearance trees built in %.0f ms\n", built,
        1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  HandTrajectory hand = HandTrajectory::BuiltIn("drag");
  hand.LoopFrom(3.0);
  DeviceModel device;
  DriverWatchdog watchdog(20e-3, 500.0);
  const double dt = 1e-3;
  int64_t now = 1'000'000'000, seq = 0;
  Eigen::Vector3d prev_hand = hand.At(0.0), wrench = Eigen::Vector3d::Zero();
  double received = -1.0;
  TickResult r;
  Snapshot snap;
  double f_sum = 0.0, worst_violation = 0.0;
  int events = 0, contacts_max = 0, quiet = 0;
  int stalled = 0, ticks = 0;  // this second's ticks, and those whose solve stalled
  bool apart = false;
  double jammed_at = -1.0, jam_violation = 0.0;
  // The wires' true gaps (testing/tube_gap.h), every `truth_every` device steps: a row held off
  // its extremum, or a section made inactive, can read ~0 while the wires cross beside it.
  std::vector<tangent::testing::Centreline> centre;
  for (const auto& surface : scene->surfaces) {
    centre.push_back(tangent::testing::SampleCentreline(surface.surface, 0, 4000));
  }
  double truest = INFINITY, truest_at = 0.0, crossed_last = -1.0;
  int64_t checks = 0, crossed = 0;  // true-gap checks, and those below −kHeldViolation
  tangent::bench::TimingJitter timing(jitter);
  for (int64_t k = 0; k < static_cast<int64_t>(seconds / dt); ++k) {
    const double t = dt * static_cast<double>(k);
    const Eigen::Vector3d rendered = watchdog.Step(t, dt, wrench, received);
    const Eigen::Vector3d target = hand.At(t);
    const Eigen::Vector3d f = device.Step(dt, target, (target - prev_hand) / dt, rendered);
    prev_hand = target;
    DeviceSample s;
    s.seq = ++seq;
    s.utime = now / 1000;
    s.received_ns = now;
    for (int i = 0; i < 3; ++i) {
      s.position[i] = device.position()[i];
      s.velocity[i] = device.velocity()[i];
    }
    s.orientation[0] = 1.0;
    for (int tick = 0; tick < 4; ++tick) {
      servo.Tick(&s, now, &r);
      now += timing.TickNs();
      ++ticks;
      // A solve at its budget, or stopped at its motion bound unconverged: it did not follow.
      stalled += r.iterations >= options.max_iterations || r.stopped_at_bound;
      worst_violation = std::max(worst_violation, r.violation);
      if (jammed_at < 0.0 && r.violation > kHeldViolation) {
        jammed_at = t;
        jam_violation = r.violation;
        std::printf("chain_soak: violation %.1e m at %.3f s (above %.0e m: not held)\n",
                    r.violation, t, kHeldViolation);
      }
      if (r.answered) {
        wrench = Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
        received = t;
      }
    }
    f_sum += f.norm();
    servo.FillSnapshot(&snap);
    contacts_max = std::max(contacts_max, snap.num_contacts);
    const bool trace = t >= trace_from && t <= trace_to;
    if (trace) {
      std::printf("t %.3f it %d viol %.1e kkt %.1e |F| %.3f lost %lld solves %lld:", t,
                  r.iterations, r.violation, r.kkt, f.norm(), static_cast<long long>(r.lost),
                  static_cast<long long>(r.solves));
      for (int c = 0; c < snap.num_contacts; ++c) {
        const TrackedContact& x = snap.contacts[c];
        std::printf(" [%d-%d b %.2e u %.4f %.4f %.4f %.4f f %.3f]", x.surface_a, x.surface_b,
                    x.beta, x.u[0], x.u[1], x.u[2], x.u[3], x.force);
      }
      for (int p = 0; p < servo.lines().pairs(); ++p) {
        if (!servo.lines().line(p)) continue;
        for (int side = 0; side < tangent::server::LineContacts::kSections; ++side) {
          const auto& x = servo.lines().section(p, side);
          std::printf(" {line %d/%d b %.2e at %.4f u %.4f %.4f %.4f %s %s}", p, side, x.ext.beta,
                      x.value, x.u[0], x.u[1], x.u[2], tangent::contact::ToString(x.ext.status),
                      tangent::contact::ToString(x.ext.kind));
        }
      }
      std::printf("\n");
    }
    if (k % pass_every == pass_every - 1 && !timing.SkipPass()) {
      link.PassInto(&servo, snap, [&](const ContactEventMsg& m, bool ok) {
        events += ok;
        if (trace) {
          std::printf("  event %s %d-%d u %.4f %.4f %.4f %.4f%s\n", m.added ? "add" : "remove",
                      m.surface_a, m.surface_b, m.u[0], m.u[1], m.u[2], m.u[3],
                      ok ? "" : " (not applied)");
        }
      });
      // A contact the stage added deeper than the bar: the rows missed a penetration (a row
      // held off its extremum reads ~0 beside it: docs/reliability.md, "Soak").
      if (jammed_at < 0.0 && link.deepest_added() < -kHeldViolation) {
        jammed_at = t;
        jam_violation = -link.deepest_added();
        std::printf(
            "chain_soak: the global stage found a contact %.1e m deep at %.3f s "
            "(above %.0e m: not held)\n",
            jam_violation, t, kHeldViolation);
      }
    }
    if (truth_every > 0 && k % truth_every == 0) {
      for (const auto& pair : scene->pairs) {
        const auto& sa = scene->surfaces[static_cast<size_t>(pair.surface_a)];
        const auto& sb = scene->surfaces[static_cast<size_t>(pair.surface_b)];
        auto placed = [&](int body, Eigen::Matrix3d* R, Eigen::Vector3d* p) {
          const auto& q = snap.q[body];
          *R = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
          *p = Eigen::Vector3d(q[0], q[1], q[2]);
        };
        Eigen::Matrix3d Ra, Rb;
        Eigen::Vector3d pa, pb;
        placed(sa.body, &Ra, &pa);
        placed(sb.body, &Rb, &pb);
        const auto& ca = centre[static_cast<size_t>(pair.surface_a)];
        const auto& cb = centre[static_cast<size_t>(pair.surface_b)];
        int ia = -1, ib = -1;
        const double gap =
            tangent::testing::CentrelineDistance(ca, Ra, pa, cb, Rb, pb, 16, &ia, &ib) - ca.radius -
            cb.radius;
        if (trace) {  // where along each wire (a fraction of its centre line) the gap is least
          std::printf("  true gap %d-%d %.2e at %.4f %.4f\n", pair.surface_a, pair.surface_b, gap,
                      static_cast<double>(ia) / static_cast<double>(ca.points.size() - 1),
                      static_cast<double>(ib) / static_cast<double>(cb.points.size() - 1));
        }
        if (gap < truest) truest = gap, truest_at = t;
        ++checks;
        if (gap < -kHeldViolation) ++crossed, crossed_last = t;
        if (jammed_at < 0.0 && gap < -kHeldViolation) {
          jammed_at = t;
          jam_violation = -gap;
          std::printf(
              "chain_soak: the wires cross by %.1e m at %.3f s (their centre lines; above "
              "%.0e m: not held)\n",
              -gap, t, kHeldViolation);
        }
      }
    }
    quiet = t > 10.0 && f.norm() < 0.02 ? quiet + 1 : 0;
    if (!apart && quiet > 5000) {
      apart = true;
      std::printf("chain_soak: apart at %.3f s (force below 0.02 N for a whole circle)\n", t - 5.0);
    }
    if ((k + 1) % 1000 == 0) {
      if (t >= from) {
        int lines = 0;
        for (int p = 0; p < servo.lines().pairs(); ++p) lines += servo.lines().line(p);
        std::printf(
            "%6.0f s  contacts %d (max %d)  lines %d (placed %lld, moved %lld, respaced %lld)  "
            "mean |F| %.3f N  "
            "events %d  violation %.1e  stalled %d\n",
            t + dt, snap.num_contacts, contacts_max, lines,
            static_cast<long long>(servo.lines().placements()),
            static_cast<long long>(servo.lines().moves()),
            static_cast<long long>(servo.lines().respaced()), f_sum / 1000.0, events,
            worst_violation, stalled);
      }
      if (jammed_at < 0.0 && 2 * stalled > ticks) {
        jammed_at = t;
        jam_violation = worst_violation;
        std::printf(
            "chain_soak: the solve stalled (its whole budget, or stopped at its motion bound) in "
            "%d of the %d ticks of the second to %.0f s: the chain does not follow the hand (not "
            "held)\n",
            stalled, ticks, t + dt);
      }
      stalled = ticks = 0;
      f_sum = 0.0;
      events = 0;
      contacts_max = 0;
      worst_violation = 0.0;
    }
  }
  if (apart) {
    std::printf("chain_soak: APART after %.0f s\n", seconds);
  } else if (jammed_at >= 0.0) {
    std::printf("chain_soak: JAMMED after %.0f s (violation %.1e m from %.3f s)\n", seconds,
                jam_violation, jammed_at);
  } else {
    std::printf("chain_soak: held after %.0f s\n", seconds);
  }
  if (truth_every > 0) {
    std::printf("chain_soak: least true gap %.1e m (at %.3f s), checked every %d ms\n", truest,
                truest_at, truth_every);
    std::printf("chain_soak: the wires crossed by more than %.0e m in %lld of %lld pair checks",
                kHeldViolation, static_cast<long long>(crossed), static_cast<long long>(checks));
    if (crossed > 0) std::printf(", the last at %.3f s", crossed_last);
    std::printf("\n");
  }
  return apart || jammed_at >= 0.0 ? 1 : 0;
}
