// The servo tick's compute on one thread, without scheduling noise (issue 6): the paperclip
// scene dragged along testing/drag_path.h (lift 6 mm over 2 s, then 4 mm circles), a device
// state every millisecond, four ticks per state, one global pass after every four ticks, its
// events applied between ticks. Reports the tick time distribution, the solver's iteration
// histogram, ticks at the iteration budget, the worst violation and complementarity (the largest
// gap of a contact carrying force). Deterministic apart from the clock: the figures to compare
// solver changes by; server_rate is the threaded test of the targets.
//
//   ./build/bench/servo_profile [--steps 8000] [--iterations 10] [--kkt 1e-8] [--points]
//   (--points: ServoOptions::line_contacts off: what line contacts cost the drag)
//
// Under callgrind (scripts/bench_report.sh) run with --instr-atstart=no: the program starts the
// instrumentation itself once the scene is loaded, which callgrind otherwise runs some 35x slower
// (18 s of the quick report); the instructions counted in ServoLoop::Tick are the same.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#endif

#include "server/global_link.h"
#include "server/servo.h"
#include "testing/drag_path.h"

using namespace tangent::server;

int main(int argc, char** argv) {
  int steps = 8000, lag = 0;
  ServoOptions so;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--points")) {
      so.line_contacts = false;
      continue;
    }
    if (i + 1 == argc) break;
    if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--iterations")) so.max_iterations = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--kkt")) so.kkt_tolerance = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--lag")) lag = std::atoi(argv[i + 1]);
    ++i;
  }
  auto scene = LoadScene(std::string(TANGENT_SCENES_DIR) + "/paperclips.json");
  ServoLoop servo(*scene, so);
  GlobalLink link(servo);
  Snapshot snap;
  TickResult r;
  int64_t now = 1'000'000'000, seq = 0;
  std::vector<double> times;
  std::vector<int> histogram(static_cast<size_t>(so.max_iterations) + 1, 0);
  double worst_violation = 0.0, worst_gap = 0.0;
  int events_applied = 0;
  std::deque<std::pair<int, ContactEventMsg>> pending;
  std::deque<std::pair<int, tangent::server::ClearanceMsg>> certificates;
  const bool verbose = std::getenv("TANGENT_VERBOSE") != nullptr;
  CALLGRIND_START_INSTRUMENTATION;  // (a no-op outside valgrind)
  for (int k = 0; k < steps; ++k) {
    const double t = 1e-3 * k;
    const DeviceSample s = tangent::bench::DragSample(++seq, t, now);
    for (int tick = 0; tick < 4; ++tick) {
      const auto t0 = std::chrono::steady_clock::now();
      servo.Tick(&s, now, &r);
      const auto t1 = std::chrono::steady_clock::now();
      times.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      ++histogram[static_cast<size_t>(std::min(r.iterations, so.max_iterations))];
      worst_violation = std::max(worst_violation, r.violation);
      if (verbose && r.violation > 1e-6) {
        std::printf("step %d tick %d: violation %.1e, %d iterations, %d contacts\n", k, tick,
                    r.violation, r.iterations, r.num_contacts);
      }
      servo.FillSnapshot(&snap);
      for (int c = 0; c < snap.num_contacts; ++c) {
        if (snap.contacts[c].force > 0.0) worst_gap = std::max(worst_gap, snap.contacts[c].beta);
        if (verbose && snap.contacts[c].force > 0.0 && snap.contacts[c].beta > 1e-8) {
          std::printf(
              "step %d tick %d: contact %d-%d carries %.2e N at a gap of %.1e m (%d iterations, "
              "kkt %.1e)\n",
              k, tick, snap.contacts[c].surface_a, snap.contacts[c].surface_b,
              snap.contacts[c].force, snap.contacts[c].beta, r.iterations, r.kkt);
        }
      }
      now += 250'000;
    }
    // The global pass on this snapshot; its events reach the servo `lag` device steps later
    // (the threaded server's pass runs beside the servo and lags it by up to a millisecond).
    link.Pass(snap, [&](const ContactEventMsg& m) { pending.push_back({k + lag, m}); });
    // Its clearance certificate with them, after them (as the engine takes it).
    certificates.push_back({k + lag, link.clearances()});
    while (!pending.empty() && pending.front().first <= k) {
      const ContactEventMsg& m = pending.front().second;
      events_applied += servo.Apply(m);
      if (verbose) {
        std::printf("step %d: event %s %d-%d u %.4f %.4f %.4f %.4f\n", k,
                    m.added ? "add" : "remove", m.surface_a, m.surface_b, m.u[0], m.u[1], m.u[2],
                    m.u[3]);
      }
      pending.pop_front();
    }
    while (!certificates.empty() && certificates.front().first <= k) {
      servo.AdoptClearances(certificates.front().second);
      certificates.pop_front();
    }
  }
  double total = 0.0;
  for (double t : times) total += t;
  std::sort(times.begin(), times.end());
  auto at = [&](double p) {
    return times[std::min(times.size() - 1, static_cast<size_t>(p * times.size()))];
  };
  std::printf(
      "servo_profile: %zu ticks, compute mean %.2f us, p50 %.1f, p90 %.1f, p99 %.1f, p99.9 %.1f, "
      "max %.1f; "
      "worst violation %.1e, loaded-contact gap %.1e, events applied %d\n",
      times.size(), total / static_cast<double>(times.size()), at(0.5), at(0.9), at(0.99),
      at(0.999), times.back(), worst_violation, worst_gap, events_applied);
  std::printf("iterations per tick:");
  for (size_t i = 0; i < histogram.size(); ++i) {
    if (histogram[i]) std::printf(" %zu: %d", i, histogram[i]);
  }
  std::printf(" (at the budget: %.2f %%)\n", 100.0 * histogram.back() / times.size());
  const ServoLoop::TrackingCounts tc = servo.Tracking();
  std::printf(
      "contact evaluations: %lld by the tracker, %lld full solves (%.2f %%), %lld lost steps\n",
      static_cast<long long>(tc.tracked), static_cast<long long>(tc.solves),
      100.0 * static_cast<double>(tc.solves) /
          static_cast<double>(std::max<int64_t>(1, tc.tracked + tc.solves)),
      static_cast<long long>(tc.lost));
  return 0;
}
