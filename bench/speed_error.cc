// Speed against error (issue 18 item 1): what each choice of servo rate, per-tick iteration
// budget and contact tracking costs in accuracy. For the paperclips, the spatial four-bar and the
// peg-in-hole scenes, each driven by three scripted hand trajectories (slow, fast, and the slow
// one with a sudden 5 mm jerk half-way), the servo runs offline on one thread: device states at
// 1 kHz, servo ticks at the swept rate (each tick takes the latest state, as tangentd's does),
// a global pass every 4 ms. Every setting is compared with a fully converged reference run at
// the same device poses and the same tick times:
//   - force error: |F − F_ref| of every answered wrench (N), RMS and max;
//   - contact-point error: every tracked contact's points against the nearest reference contact
//     of the same pair at each global pass (m), RMS and max; a contact the reference does not
//     have (or the reverse) is counted as unmatched;
//   - constraint violation of the setting's own ticks (m), RMS and max;
//   - tick p50/p99 (µs); the achieved rate: the nominal rate when the tick p99 fits in a period,
//     else the rate whose period it fills; and the servo thread's CPU share as tangentd's engine
//     would take it (server/engine.cc: it sleeps until spin_us before each deadline, then spins,
//     and also spins around each expected device state): the fraction of time the thread is
//     awake. The machine's wake-up lateness (a thread sleeping to absolute deadlines with 1 ns
//     timer slack) is measured in the same run and printed: the engine's spin absorbs lateness
//     up to spin_us; bench/server_rate measures the real loop with it.
// The swept settings: the budget (1, 2, 3, 5, 10 iterations, and converged) at every rate with
// the default tracking; the tracker's corrector steps (0–3), each with the exact acceptance (the
// tracked point is taken only at the extremal solver's tolerance, else a full solve) and with
// the tracker's own ("tracked": its point taken as it stands), at the default budget and every
// rate. Per scene, the Pareto front over (force RMS error ↓, achieved rate ↑, CPU share ↓;
// pooled over the three trajectories) is marked, and whether the default settings (4 kHz, 10
// iterations, one corrector, exact) lie on it is printed. Rate and CPU are both objectives:
// against a same-rate reference a converged tick has the same error at any rate, and what a
// higher rate buys (an answer sooner after each device state: half a period on average) it pays
// for in the core's time, which the global stage and the LCM bridge share on two cores.
//
//   ./build/bench/speed_error [--seconds 2] [--rates 1000,2000,4000,10000,20000]
//                             [--scenes paperclips,fourbar_point,peg_in_hole] [--csv out.csv]
//                             [--quick]   (one trajectory, three budgets, two rates: CI smoke)

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "bench/sample_stats.h"
#include "server/engine.h"
#include "server/global_link.h"
#include "server/phantom.h"
#include "server/servo.h"
#include "testing/drag_path.h"

using namespace tangent::server;

namespace {

using tangent::bench::Quantile;

constexpr int kConverged = 200;  // the "converged" budget: the KKT tolerance stops it first
constexpr double kDefaultRate = 4000.0;
constexpr double kJerk = 5e-3;  // m, the sudden step of the jerk trajectory

struct Hand {
  std::string name;
  std::function<Eigen::Vector3d(double)> at;  ///< device position (m) at time t (s)
};

struct SceneCase {
  std::string scene;
  std::function<Eigen::Vector3d(double)> path;  ///< the scene's base hand path
  double slow = 1.0, fast = 4.0;                ///< time scales of the slow and fast runs
};

std::vector<Hand> HandsOf(const SceneCase& c, double seconds, bool quick) {
  const auto path = c.path;
  const double slow = c.slow, fast = c.fast, half = 0.5 * seconds;
  std::vector<Hand> hands = {{"slow", [=](double t) { return path(slow * t); }}};
  if (quick) return hands;
  hands.push_back({"fast", [=](double t) { return path(fast * t); }});
  hands.push_back({"jerk", [=](double t) {
                     return Eigen::Vector3d(path(slow * t) + (t >= half
                                                                  ? Eigen::Vector3d(kJerk, 0, 0)
                                                                  : Eigen::Vector3d::Zero()));
                   }});
  return hands;
}

SceneCase CaseOf(const std::string& name) {
  if (name == "paperclips") return {name, tangent::bench::DragPath, 2.0, 8.0};
  if (name == "peg_in_hole") {
    std::ifstream f(std::string(TANGENT_SCENES_DIR) + "/peg_in_hole.path.csv");
    std::stringstream text;
    text << f.rdbuf();
    auto path = std::make_shared<HandTrajectory>(
        HandTrajectory::FromCsv(text.str(), "peg_in_hole.path.csv"));
    return {name, [path](double t) { return path->At(t); }, 4.0, 10.0};
  }
  // Any other scene (the four-bar): circles of 1 cm radius in the device's x–y plane, 4 s a turn.
  return {name,
          [](double t) {
            const double a = 2 * std::numbers::pi * t / 4.0;
            return Eigen::Vector3d(1e-2 * std::sin(a), 1e-2 * (std::cos(a) - 1.0), 0.0);
          },
          1.0, 4.0};
}

struct Setting {
  int budget = 10;
  int correctors = 1;
  bool exact = true;
  double rate = kDefaultRate;
  bool operator==(const Setting&) const = default;
  bool is_default() const {
    return budget == 10 && correctors == 1 && exact && rate == kDefaultRate;
  }
  std::string tracking() const {
    return std::to_string(correctors) + (exact ? " exact" : " tracked");
  }
};

// What a run records at each tick and global pass, for the comparison with the reference.
struct Trace {
  std::vector<double> tick_us, violation;
  std::vector<Eigen::Vector3d> force;                 ///< answered wrenches' force; NaN where none
  std::vector<std::vector<TrackedContact>> contacts;  ///< at each global pass
  int budget_ticks = 0;
};

Trace Simulate(const Scene& scene, const Hand& hand, const Setting& s, double seconds) {
  ServoOptions options;
  options.max_iterations = s.budget;
  options.tracking.corrector_steps = s.correctors;
  // "tracked": the tracker's point is the contact when its residual is within the tracker's own
  // basin test (contact::TrackerOptions::max_residual), so a full solve runs only when lost.
  options.tracking.accept_residual = s.exact ? 1e-12 : 1e-3;
  ServoLoop servo(scene, options);
  GlobalLink link(servo);
  Trace tr;
  const int64_t ticks = static_cast<int64_t>(std::llround(seconds * s.rate));
  tr.tick_us.reserve(static_cast<size_t>(ticks));
  tr.violation.reserve(static_cast<size_t>(ticks));
  tr.force.reserve(static_cast<size_t>(ticks));
  const int64_t t0 = 1'000'000'000;
  DeviceSample sample;
  int64_t sample_index = -1, pass_index = 0;
  TickResult r;
  Snapshot snap;
  for (int64_t i = 0; i < ticks; ++i) {
    const int64_t now = t0 + static_cast<int64_t>(std::llround(1e9 * i / s.rate));
    const int64_t k = (now - t0) / 1'000'000;  // the latest 1 kHz device state
    if (k != sample_index) {
      sample_index = k;
      sample = tangent::bench::DragSample(k + 1, 1e-3 * static_cast<double>(k), t0 + k * 1'000'000);
      const Eigen::Vector3d p = hand.at(1e-3 * static_cast<double>(k));
      for (int j = 0; j < 3; ++j) sample.position[j] = p[j];
    }
    const auto c0 = std::chrono::steady_clock::now();
    servo.Tick(&sample, now, &r);
    tr.tick_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - c0).count());
    tr.violation.push_back(r.violation);
    tr.budget_ticks += r.iterations >= s.budget;
    tr.force.push_back(
        r.answered ? Eigen::Vector3d(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2])
                   : Eigen::Vector3d::Constant(std::nan("")));
    if ((now - t0) / 4'000'000 >= pass_index) {
      ++pass_index;
      servo.FillSnapshot(&snap);
      tr.contacts.emplace_back(snap.contacts, snap.contacts + snap.num_contacts);
      link.PassInto(&servo, snap);
    }
  }
  return tr;
}

// Sums of squares and maxima, pooled over a scene's trajectories.
struct ErrorSums {
  double sq = 0.0, max = 0.0;
  int64_t n = 0;
  void Add(double e) {
    sq += e * e;
    max = std::max(max, e);
    ++n;
  }
  void Add(const ErrorSums& o) {
    sq += o.sq;
    max = std::max(max, o.max);
    n += o.n;
  }
  double Rms() const { return n ? std::sqrt(sq / static_cast<double>(n)) : 0.0; }
};

struct Row {
  std::string scene, hand;
  Setting setting;
  double p50 = 0, p99 = 0, mean = 0, achieved = 0, cpu = 0;
  ErrorSums force, point, violation;
  int64_t unmatched = 0, ticks = 0;
  int budget_ticks = 0;
  bool pareto = false;
};

double PointDistance(const TrackedContact& a, const TrackedContact& b) {
  double da = 0.0, db = 0.0;
  for (int j = 0; j < 3; ++j) {
    da += (a.p_a[j] - b.p_a[j]) * (a.p_a[j] - b.p_a[j]);
    db += (a.p_b[j] - b.p_b[j]) * (a.p_b[j] - b.p_b[j]);
  }
  return std::sqrt(std::max(da, db));
}

// Contacts of the same pair farther apart than this are different contacts (unmatched).
constexpr double kSameContact = 2e-3;  // m

// Wake-up lateness p99 (µs) of a thread sleeping to absolute deadlines 250 µs apart for
// `seconds`: what the servo thread's own clock_nanosleep adds to every tick on this machine.
double WakeupLatenessP99(double seconds) {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);  // as the engine's servo thread
  std::vector<double> late;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  const int n = static_cast<int>(seconds * 4000.0);
  late.reserve(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    next.tv_nsec += 250'000;
    if (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    late.push_back(1e-3 * static_cast<double>((now.tv_sec - next.tv_sec) * 1'000'000'000 +
                                              (now.tv_nsec - next.tv_nsec)));
  }
  return Quantile(late, 0.99);
}

// The engine's timing (server/engine.h) for a servo at `rate` whose ticks take `tick_p99` and
// `tick_mean` µs: the rate its compute allows and the share of a core its thread is awake.
struct EngineTiming {
  double achieved = 0.0, cpu = 0.0;
};
EngineTiming EngineAt(double rate, double tick_p99, double tick_mean) {
  const EngineOptions e;
  EngineTiming t;
  t.achieved = tick_p99 <= 1e6 / rate ? rate : 1e6 / tick_p99;
  // Awake: [deadline − spin, deadline + tick] for each tick, and [arrival − lead, arrival + lag]
  // for each 1 kHz device state; their union's share of time, averaged over the arrivals'
  // phase against the ticks (1 µs grid over one millisecond).
  const double p = 1e6 / t.achieved;
  double awake = 0.0;
  const int phases = 8;
  for (int k = 0; k < phases; ++k) {
    const double phase = 1000.0 * k / phases;
    int busy = 0;
    for (int us = 0; us < 1000; ++us) {
      const double x = us + 0.5;
      const double since_tick = std::fmod(x, p);  // time after the last deadline
      bool on = since_tick < tick_mean || p - since_tick < e.spin_us;
      if (e.spin_for_device) {
        const double since_arrival = std::fmod(x - phase + 1000.0, 1000.0);
        on = on || since_arrival < e.device_lag_us || 1000.0 - since_arrival < e.device_lead_us;
      }
      busy += on;
    }
    awake += busy / 1000.0;
  }
  t.cpu = std::min(1.0, awake / phases);
  return t;
}

Row Compare(const Trace& run, const Trace& ref, const Setting& s) {
  Row row;
  row.setting = s;
  row.ticks = static_cast<int64_t>(run.tick_us.size());
  row.budget_ticks = run.budget_ticks;
  row.p50 = Quantile(run.tick_us, 0.5);
  row.p99 = Quantile(run.tick_us, 0.99);
  row.mean = tangent::bench::Mean(run.tick_us);
  const EngineTiming timing = EngineAt(s.rate, row.p99, row.mean);
  row.achieved = timing.achieved;
  row.cpu = timing.cpu;
  for (size_t i = 0; i < run.force.size() && i < ref.force.size(); ++i) {
    row.violation.Add(run.violation[i]);
    if (run.force[i].allFinite() && ref.force[i].allFinite())
      row.force.Add((run.force[i] - ref.force[i]).norm());
  }
  auto match = [&](const std::vector<TrackedContact>& mine,
                   const std::vector<TrackedContact>& theirs, bool record) {
    for (const TrackedContact& c : mine) {
      double best = std::numeric_limits<double>::infinity();
      for (const TrackedContact& o : theirs) {
        if (o.surface_a == c.surface_a && o.surface_b == c.surface_b)
          best = std::min(best, PointDistance(c, o));
      }
      if (best > kSameContact) {
        ++row.unmatched;
      } else if (record) {
        row.point.Add(best);
      }
    }
  };
  for (size_t k = 0; k < run.contacts.size() && k < ref.contacts.size(); ++k) {
    match(run.contacts[k], ref.contacts[k], true);
    match(ref.contacts[k], run.contacts[k], false);
  }
  return row;
}

std::vector<int> ParseList(const char* text) {
  std::vector<int> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  bool quick = false;
  std::vector<int> rates = {1000, 2000, 4000, 10000, 20000};
  std::vector<std::string> scenes = {"paperclips", "fourbar_point", "peg_in_hole"};
  std::string csv;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--quick")) {
      quick = true;
    } else if (!std::strcmp(argv[i], "--seconds") && has_value) {
      seconds = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--rates") && has_value) {
      rates = ParseList(argv[++i]);
    } else if (!std::strcmp(argv[i], "--csv") && has_value) {
      csv = argv[++i];
    } else if (!std::strcmp(argv[i], "--scenes") && has_value) {
      scenes.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) scenes.push_back(item);
    } else {
      std::fprintf(stderr,
                   "speed_error: unknown or incomplete argument \"%s\"\n"
                   "usage: speed_error [--seconds S] [--rates R1,R2,...] [--scenes A,B,...] "
                   "[--csv FILE] [--quick]\n",
                   argv[i]);
      return 2;
    }
  }
  if (!(seconds > 0.0) || rates.empty() || scenes.empty()) {
    std::fprintf(stderr,
                 "speed_error: --seconds must be positive, --rates and --scenes not empty\n");
    return 2;
  }
  std::vector<int> budgets = {1, 2, 3, 5, 10, kConverged};
  if (quick) {
    budgets = {1, 10, kConverged};
    rates = {1000, 4000};
  }

  std::vector<Row> rows;
  const double wakeup_p99 = WakeupLatenessP99(quick ? 0.2 : 2.0);
  std::printf(
      "speed_error: %.1f s per trajectory, device states at 1 kHz, global pass every 4 ms; "
      "wake-up lateness p99 %.1f us (same run)\n",
      seconds, wakeup_p99);
  for (const std::string& name : scenes) {
    const SceneCase sc = CaseOf(name);
    const std::unique_ptr<Scene> scene =
        LoadScene(std::string(TANGENT_SCENES_DIR) + "/" + name + ".json");
    const bool has_contacts = !scene->pairs.empty();
    std::vector<Setting> settings;
    for (int rate : rates) {
      for (int b : budgets) settings.push_back({b, 1, true, static_cast<double>(rate)});
      if (!has_contacts || quick) continue;  // tracking is moot without contacts
      for (int c = 0; c <= 3; ++c) {
        for (bool exact : {true, false}) {
          if (c == 1 && exact) continue;  // the default, in the budget row
          settings.push_back({10, c, exact, static_cast<double>(rate)});
        }
      }
    }
    for (const Hand& hand : HandsOf(sc, seconds, quick)) {
      for (int rate : rates) {
        const Setting ref_setting{kConverged, 1, true, static_cast<double>(rate)};
        const Trace ref = Simulate(*scene, hand, ref_setting, seconds);
        for (const Setting& s : settings) {
          if (s.rate != rate) continue;
          const bool is_ref = s == ref_setting;
          Row row = Compare(is_ref ? ref : Simulate(*scene, hand, s, seconds), ref, s);
          row.scene = name;
          row.hand = hand.name;
          rows.push_back(row);
        }
      }
    }
  }

  // Per scene and setting, pooled over the trajectories: the Pareto front over (force RMS error,
  // achieved rate, CPU share). A setting is dominated when another is no worse in all three and
  // better in one by more than the timing noise of a shared machine (10 %; the same setting run
  // twice differs by up to ~8 % in mean tick here) or, for errors, 2 % and 1e-9 N (rounding).
  constexpr double kTimingNoise = 0.10;
  struct Pooled {
    std::string scene;
    Setting setting;
    double achieved = std::numeric_limits<double>::infinity(), p99 = 0.0, cpu = 0.0;
    ErrorSums force, point, violation;
    int64_t unmatched = 0;
    bool pareto = true;
  };
  std::vector<Pooled> pooled;
  for (const Row& r : rows) {
    auto it = std::find_if(pooled.begin(), pooled.end(), [&](const Pooled& p) {
      return p.scene == r.scene && p.setting == r.setting;
    });
    if (it == pooled.end()) {
      Pooled p;
      p.scene = r.scene;
      p.setting = r.setting;
      pooled.push_back(p);
      it = pooled.end() - 1;
    }
    it->achieved = std::min(it->achieved, r.achieved);
    it->p99 = std::max(it->p99, r.p99);
    it->cpu = std::max(it->cpu, r.cpu);
    it->force.Add(r.force);
    it->point.Add(r.point);
    it->violation.Add(r.violation);
    it->unmatched += r.unmatched;
  }
  auto better = [](double a, double b, double rel, double abs) {
    return a < b - std::max(rel * b, abs);
  };
  // A setting whose rate the engine cannot keep (achieved below 90 % of nominal on some
  // trajectory) cannot be run as set: it is not on the front, nor does it dominate.
  auto achievable = [](const Pooled& p) { return p.achieved >= 0.9 * p.setting.rate; };
  for (Pooled& p : pooled) {
    if (!achievable(p)) {
      p.pareto = false;
      continue;
    }
    for (const Pooled& o : pooled) {
      if (&o == &p || o.scene != p.scene || !achievable(o)) continue;
      const bool no_worse = o.achieved >= p.achieved * (1 - kTimingNoise) &&
                            o.cpu <= p.cpu * (1 + kTimingNoise) &&
                            o.force.Rms() <= p.force.Rms() * 1.02 + 1e-9;
      const bool strictly = better(p.achieved, o.achieved, kTimingNoise, 0.0) ||
                            better(o.cpu, p.cpu, kTimingNoise, 0.0) ||
                            better(o.force.Rms(), p.force.Rms(), 0.02, 1e-9);
      if (no_worse && strictly) {
        p.pareto = false;
        break;
      }
    }
  }

  std::printf(
      "\n| scene | hand | rate (Hz) | budget | tracking | achieved (Hz) | CPU (core) | tick p50 "
      "(us) | tick p99 "
      "(us) | at budget | force err RMS (N) | force err max (N) | point err RMS (m) | point "
      "err max (m) | unmatched | violation RMS (m) | violation max (m) |\n");
  std::printf(
      "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | "
      "--- | --- | --- |\n");
  auto budget_name = [](int b) {
    return b == kConverged ? std::string("conv") : std::to_string(b);
  };
  for (const Row& r : rows) {
    std::printf(
        "| %s | %s | %.0f | %s | %s | %.0f | %.3f | %.2f | %.2f | %.1f %% | %.2e | %.2e | %.2e | "
        "%.2e | %lld | %.1e | %.1e |\n",
        r.scene.c_str(), r.hand.c_str(), r.setting.rate, budget_name(r.setting.budget).c_str(),
        r.setting.tracking().c_str(), r.achieved, r.cpu, r.p50, r.p99,
        100.0 * r.budget_ticks / std::max<int64_t>(1, r.ticks), r.force.Rms(), r.force.max,
        r.point.Rms(), r.point.max, static_cast<long long>(r.unmatched), r.violation.Rms(),
        r.violation.max);
  }
  std::printf(
      "\nPareto front per scene (force RMS error down, achieved rate up, CPU share down; all "
      "trajectories pooled):\n");
  for (const std::string& name : scenes) {
    int on = 0;
    const Pooled* def = nullptr;
    for (const Pooled& p : pooled) {
      if (p.scene != name) continue;
      on += p.pareto;
      if (p.setting.is_default()) def = &p;
    }
    std::printf("%s: %d settings on the front; default (4 kHz, 10 iterations, 1 exact): %s\n",
                name.c_str(), on,
                !def          ? "not run"
                : def->pareto ? "ON the front"
                              : "NOT on the front");
    for (const Pooled& p : pooled) {
      if (p.scene == name && p.pareto) {
        std::printf(
            "  front: %5.0f Hz budget %-4s %-10s achieved %6.0f Hz CPU %.3f force RMS %.2e N%s\n",
            p.setting.rate, budget_name(p.setting.budget).c_str(), p.setting.tracking().c_str(),
            p.achieved, p.cpu, p.force.Rms(), p.setting.is_default() ? "  (default)" : "");
      }
    }
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "scene,hand,rate,budget,correctors,exact,achieved,cpu,tick_p50_us,tick_p99_us,budget_"
           "ticks,"
           "ticks,force_rms,force_max,point_rms,point_max,unmatched,violation_rms,violation_max,"
           "pareto,default\n";
    for (const Row& r : rows) {
      bool front = false;
      for (const Pooled& p : pooled) {
        if (p.scene == r.scene && p.setting == r.setting) front = p.pareto;
      }
      out << r.scene << ',' << r.hand << ',' << r.setting.rate << ','
          << budget_name(r.setting.budget) << ',' << r.setting.correctors << ','
          << (r.setting.exact ? 1 : 0) << ',' << r.achieved << ',' << r.cpu << ',' << r.p50 << ','
          << r.p99 << ',' << r.budget_ticks << ',' << r.ticks << ',' << r.force.Rms() << ','
          << r.force.max << ',' << r.point.Rms() << ',' << r.point.max << ',' << r.unmatched << ','
          << r.violation.Rms() << ',' << r.violation.max << ',' << (front ? 1 : 0) << ','
          << (r.setting.is_default() ? 1 : 0) << '\n';
    }
  }
  return 0;
}
