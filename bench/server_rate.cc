// The servo loop's rate test (issue 6): the paperclip scene (three clips, two surface contacts,
// one grasped) on the Engine's two threads — servo loop pinned to core 0 at 4 kHz, global contact
// stage on core 1 — for --seconds (default 60), with the hand dragging the chain (the phantom's
// "drag" path, fed at 1 kHz by this process's main thread, which also drains the wrenches as the
// LCM bridge would). Reports the tick compute-time distribution, late ticks, overruns,
// constraint violation, global passes, and the machine's own wake-up jitter measured in the same
// run (the feeding thread's lateness after each 1 ms clock_nanosleep, timer slack 1 ns).
//
// With --scene NAME, scenes/NAME.json instead, its hand following scenes/NAME.path.csv when
// there is one (the peg-in-hole scene: over the plate, across the rim, into the hole, round
// its wall), looped.
//
//   ./build/bench/server_rate [--seconds 60] [--rate 4000] [--scene paperclips]
//                             [--lines 1]  (0: ServoOptions::line_contacts off, for the cost)

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "server/engine.h"
#include "server/phantom.h"
#include "server/scene.h"
#include "testing/drag_path.h"

using namespace tangent::server;

int main(int argc, char** argv) {
  double seconds = 60.0, rate = 4000.0;
  bool spin_for_device = true;
  std::string scene_name = "paperclips";
  bool lines = true;
  const bool verbose = std::getenv("TANGENT_VERBOSE") != nullptr;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--rate")) rate = std::atof(argv[i + 1]);
    if (!std::strcmp(argv[i], "--spin-for-device")) spin_for_device = std::atoi(argv[i + 1]) != 0;
    if (!std::strcmp(argv[i], "--scene")) scene_name = argv[i + 1];
    if (!std::strcmp(argv[i], "--lines")) lines = std::atoi(argv[i + 1]) != 0;
  }
  const std::string base = std::string(TANGENT_SCENES_DIR) + "/" + scene_name;
  auto scene = LoadScene(base + ".json");
  std::unique_ptr<HandTrajectory> path;
  if (std::filesystem::exists(base + ".path.csv")) {
    std::ifstream f(base + ".path.csv");
    std::stringstream text;
    text << f.rdbuf();
    path =
        std::make_unique<HandTrajectory>(HandTrajectory::FromCsv(text.str(), base + ".path.csv"));
    path->LoopFrom(0.0);
  }
  EngineOptions eo;
  eo.rate_hz = rate;
  eo.servo.line_contacts = lines;
  eo.spin_for_device = spin_for_device;
  Engine engine(*scene, eo);
  std::printf(
      "server_rate: %s, %d contacts at rest, servo %.0f Hz on core %d, global stage "
      "on core %d, %.0f s\n",
      scene_name.c_str(), engine.servo().active_contacts(), rate, eo.servo_cpu, eo.global_cpu,
      seconds);
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  engine.Start();
  // This thread stands for the LCM bridge: off the servo's core, as tangentd keeps it.
  PinToCore(eo.global_cpu);
  const int64_t start = MonotonicNs();
  int64_t next = start, seq = 0;
  std::vector<double> jitter;
  jitter.reserve(static_cast<size_t>(seconds * 1000) + 16);
  double max_violation = 0.0, max_force = 0.0;
  int max_contacts = 0;
  LoopCounters c;
  WrenchSample w;
  while (true) {
    next += 1000000;
    timespec ts{static_cast<time_t>(next / 1000000000LL), static_cast<long>(next % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const int64_t now = MonotonicNs();
    jitter.push_back(1e-3 * static_cast<double>(now - next));
    const double t = 1e-9 * static_cast<double>(now - start);
    if (t > seconds) break;
    DeviceSample sample = tangent::bench::DragSample(++seq, t, now);
    if (path) {
      const Eigen::Vector3d p = path->At(t);
      for (int i = 0; i < 3; ++i) sample.position[i] = p[i];
    }
    engine.Publish(sample);
    while (engine.wrenches().Pop(&w)) {
      max_force = std::max(max_force, std::sqrt(w.force[0] * w.force[0] + w.force[1] * w.force[1] +
                                                w.force[2] * w.force[2]));
    }
    JournalEntry j;
    char line[200];
    while (engine.journal().Pop(&j)) {
      if (!verbose) continue;
      FormatJournalEntry(j, start, line, sizeof(line));
      std::printf("  %s\n", line);
    }
    engine.counters().Read(&c);
    max_violation = std::max(max_violation, c.max_violation);
    max_contacts = std::max(max_contacts, c.num_contacts);
  }
  engine.Stop();
  engine.counters().Read(&c);
  std::vector<uint64_t> h(DurationHistogram::kBins + 1), g(DurationHistogram::kBins + 1);
  engine.compute_histogram().Copy(h.data());
  engine.global_histogram().Copy(g.data());
  std::sort(jitter.begin(), jitter.end());
  auto jq = [&](double q) {
    return jitter[std::min(jitter.size() - 1,
                           static_cast<size_t>(q * static_cast<double>(jitter.size())))];
  };
  const double p50 = DurationHistogram::Quantile(h.data(), 0.5);
  const double p99 = DurationHistogram::Quantile(h.data(), 0.99);
  const double p999 = DurationHistogram::Quantile(h.data(), 0.999);
  const int64_t scheduled = c.ticks - c.early_ticks;
  const double late_fraction =
      scheduled > 0 ? static_cast<double>(c.late) / static_cast<double>(scheduled) : 0.0;
  std::printf(
      "ticks %lld (%.0f Hz), early (device-triggered) %lld, iterations/tick %.2f\n",
      static_cast<long long>(c.ticks), static_cast<double>(c.ticks) / seconds,
      static_cast<long long>(c.early_ticks),
      static_cast<double>(c.iterations) / static_cast<double>(std::max<int64_t>(1, c.ticks)));
  std::printf(
      "tick compute time: p50 %.2f us, p99 %.2f us, p99.9 %.2f us, max %.1f us "
      "(capacity 1/p99 = %.0f Hz)\n",
      p50, p99, p999, engine.compute_histogram().max(), 1e6 / p99);
  std::printf(
      "late ticks (finished > half a period after the deadline): %lld of %lld = %.3f %%; "
      "overruns %lld\n",
      static_cast<long long>(c.late), static_cast<long long>(scheduled), 100.0 * late_fraction,
      static_cast<long long>(c.overruns));
  std::printf(
      "machine wake-up jitter (1 ms sleeps, same run): p50 %.1f us, p99 %.1f us, p99.9 "
      "%.1f us, max %.1f us\n",
      jq(0.5), jq(0.99), jq(0.999), jitter.back());
  std::printf(
      "global stage: %lld passes (%.0f Hz), p50 %.1f us, max %.1f us; contact events %lld, "
      "dropped %lld; contacts up to %d\n",
      static_cast<long long>(engine.global_passes()),
      static_cast<double>(engine.global_passes()) / seconds,
      DurationHistogram::Quantile(g.data(), 0.5), engine.global_histogram().max(),
      static_cast<long long>(c.events_applied), static_cast<long long>(c.events_dropped),
      max_contacts);
  std::printf("constraint violation during the run: max %.1e (target 1e-6); max force %.2f N\n",
              max_violation, max_force);
  std::printf(
      "targets: p99 <= 50 us %s, p99.9 <= 100 us %s, late < 0.5 %% at 4 kHz %s, "
      "violation <= 1e-6 %s\n",
      p99 <= 50 ? "met" : "NOT MET", p999 <= 100 ? "met" : "NOT MET",
      late_fraction < 0.005 ? "met" : "NOT MET", max_violation <= 1e-6 ? "met" : "NOT MET");
  return 0;
}
