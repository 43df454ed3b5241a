// tangent-phantom: a simulated PHANToM-class client in its own process. Publishes device states
// at 1 kHz while a scripted hand drives the stylus through a hand impedance, applies the
// wrenches tangentd sends back, and reports round-trip latency (against a bare LCM ping-pong
// measured in the same run), lost and late answers, forces, and an energy (passivity) check.

#include <sys/prctl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <tangent/device_state_t.hpp>
#include <tangent/loop_stats_t.hpp>
#include <tangent/wrench_t.hpp>

#include "server/lcm_subscriptions.h"
#include "server/lockfree.h"
#include "server/phantom.h"

namespace {

using tangent::server::DeviceModel;
using tangent::server::HandTrajectory;
using tangent::server::Percentiles;

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }

int64_t NowNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

void SleepUntil(int64_t t_ns) {
  timespec ts{static_cast<time_t>(t_ns / 1000000000LL), static_cast<long>(t_ns % 1000000000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

struct LatestWrench {
  double force[3] = {0, 0, 0};
  double torque[3] = {0, 0, 0};
  int64_t seq = -1;
  int state = 0;
  int64_t received_ns = 0;  ///< this process's clock
  double latency_us = 0.0;  ///< round trip of the state it answers (0 for timeout wrenches)
};

struct Receiver {
  tangent::server::Seqlock<LatestWrench> wrench;
  std::vector<double> latency_us, ping_us;
  std::vector<int64_t> answered_seq;
  int64_t late = 0, bad = 0, foreign = 0, timeout_wrenches = 0, fault_wrenches = 0;
  // The safety contract checked on every wrench of this session, on the server's clock
  // (wrench_t.server_utime): |F| ≤ max_force, |ΔF| ≤ max_force_rate × Δt (docs/server.md).
  double max_force = 3.3, max_force_rate = 500.0;
  double wrench_force_max = 0.0, worst_rate_excess = 0.0;
  int64_t over_max = 0, over_rate = 0;
  // A silent device's force only falls: timeout wrenches (state 2) whose |F| rose above the
  // wrench before them (docs/server.md, "Device sessions").
  int64_t timeout_force_rises = 0;
  double last_force[3] = {0, 0, 0};
  int64_t last_server_utime = 0;
  int last_state = -1;
  bool have_last = false;
  std::atomic<int64_t> first_answer_ns{0};
  int64_t device_id = 1, session = 0;
  double late_threshold_us = 1000.0;
  // Loop statistics from tangentd (for the status line).
  std::atomic<double> loop_rate{0.0};
  std::atomic<int> contacts{0};
  std::atomic<double> violation{0.0};

  void OnWrench(const tangent::wrench_t* m) {
    // Only the wrenches of this client's own session (another client's, or a previous run's
    // still in flight, are not for this device).
    if (m->device_id != device_id || m->session != session) {
      ++foreign;
      return;
    }
    const int64_t now = NowNs();
    bool finite = true;
    for (int i = 0; i < 3; ++i) finite = finite && std::isfinite(m->force[i]);
    if (!finite) {
      ++bad;
      return;
    }
    CheckContract(m);
    double round_trip = 0.0;
    if (m->state == 2) {
      ++timeout_wrenches;  // the server heard nothing from us: not an answer
    } else {
      if (m->state == 3) ++fault_wrenches;
      const double lat = 1e-3 * static_cast<double>(now / 1000 * 1000 - m->utime * 1000);
      latency_us.push_back(lat);
      round_trip = lat;
      if (lat > late_threshold_us) ++late;
      answered_seq.push_back(m->seq);
      if (first_answer_ns.load() == 0) first_answer_ns.store(now);
    }
    LatestWrench w;
    std::memcpy(w.force, m->force, sizeof(w.force));
    std::memcpy(w.torque, m->torque, sizeof(w.torque));
    w.seq = m->seq;
    w.state = m->state;
    w.received_ns = now;
    w.latency_us = round_trip;
    wrench.Write(w);
  }
  void CheckContract(const tangent::wrench_t* m) {
    const double f = std::sqrt(m->force[0] * m->force[0] + m->force[1] * m->force[1] +
                               m->force[2] * m->force[2]);
    wrench_force_max = std::max(wrench_force_max, f);
    if (f > max_force + 1e-9) ++over_max;
    if (have_last) {
      double step2 = 0.0;
      for (int i = 0; i < 3; ++i)
        step2 += (m->force[i] - last_force[i]) * (m->force[i] - last_force[i]);
      // server_utime is in whole µs: a µs of rounding at each end.
      const double dt = 1e-6 * static_cast<double>(m->server_utime - last_server_utime + 2);
      const double excess = std::sqrt(step2) - max_force_rate * std::max(dt, 0.0);
      worst_rate_excess = std::max(worst_rate_excess, excess);
      if (excess > 1e-9) ++over_rate;
      const double last = std::sqrt(last_force[0] * last_force[0] + last_force[1] * last_force[1] +
                                    last_force[2] * last_force[2]);
      // (The ramp scales the force by factors ≤ 1: in exact arithmetic it never rises; 1e-12 N
      // is far above the rounding of that product, far below any force a hand could feel.)
      if (m->state == 2 && last_state == 2 && f > last + 1e-12) ++timeout_force_rises;
    }
    std::memcpy(last_force, m->force, sizeof(last_force));
    last_server_utime = m->server_utime;
    last_state = m->state;
    have_last = true;
  }
  void OnPong(const void* data, uint32_t size) {
    if (size != sizeof(int64_t)) return;
    int64_t sent;
    std::memcpy(&sent, data, sizeof(sent));
    ping_us.push_back(1e-3 * static_cast<double>(NowNs() - sent));
  }
  void OnStats(const tangent::loop_stats_t* m) {
    loop_rate.store(m->loop_rate_hz);
    contacts.store(m->num_contacts);
    violation.store(m->max_violation);
  }
};

struct PhantomOptions {
  std::string url = "udpm://239.255.76.68:7668?ttl=0", trajectory = "drag", csv_log;
  std::string device_ch = "TANGENT_DEVICE", wrench_ch = "TANGENT_WRENCH",
              stats_ch = "TANGENT_STATS";
  std::string ping_ch = "TANGENT_PING", pong_ch = "TANGENT_PONG";
  double duration = 10.0, rate = 1000.0, ping_rate = 100.0, coupling_stiffness = 300.0;
  double silence_at = -1.0, silence_for = 0.0;
  double watchdog_ms = 20.0, watchdog_rate = 500.0;
  double max_force_rate = 500.0;  ///< the server's force-rate limit, N/s (checked on wrenches)
  double loop_from = -1.0;
  int64_t device_id = 1, session = 0;
  int inject_bad = 0;
  bool status = false;
  tangent::server::DeviceModelOptions dm;
};

void AddOptions(CLI::App* app, PhantomOptions* o) {
  app->add_option("--lcm-url", o->url, "LCM URL");
  app->add_option("--trajectory", o->trajectory,
                  "built-in hand trajectory (drag, circle, pull, hold) or a CSV file t,x,y,z");
  app->add_option("--duration", o->duration, "seconds")->check(CLI::Range(0.1, 86400.0));
  app->add_option("--loop-from", o->loop_from,
                  "repeat the trajectory from this time (s) after its end (drag: 3; soak runs)");
  app->add_option("--rate", o->rate, "device rate, Hz")->check(CLI::Range(10.0, 10000.0));
  app->add_option("--ping-rate", o->ping_rate, "bare LCM ping-pong rate, Hz (0: off)");
  app->add_option("--log", o->csv_log, "CSV log of every device step");
  app->add_option("--coupling-stiffness", o->coupling_stiffness,
                  "the server's coupling stiffness (N/m), for the passivity bound");
  app->add_option("--silence-at", o->silence_at, "stop publishing at this time (s; timeout test)");
  app->add_option("--silence-for", o->silence_for, "... for this long (s)");
  app->add_option(
      "--inject-bad", o->inject_bad,
      "every N-th message is bad (NaN, non-unit quaternion, repeated seq, jump, outside the "
      "workspace in turn)");
  app->add_option("--device-id", o->device_id, "this device's id (device_state_t.device_id)");
  app->add_option("--session", o->session,
                  "session nonce (default: drawn at random at start; a new one takes over)");
  app->add_option("--watchdog-ms", o->watchdog_ms,
                  "no wrench for this long: the device ramps its own force to zero, ms")
      ->check(CLI::Range(1.0, 10000.0));
  app->add_option("--watchdog-rate", o->watchdog_rate, "... at this rate, N/s")
      ->check(CLI::Range(1.0, 1e6));
  app->add_option("--device-channel", o->device_ch);
  app->add_option("--wrench-channel", o->wrench_ch);
  app->add_option("--stats-channel", o->stats_ch);
  app->add_option("--mass", o->dm.mass, "device apparent mass, kg");
  app->add_option("--max-force", o->dm.max_force, "device force saturation, N");
  app->add_option("--max-force-rate", o->max_force_rate,
                  "the server's force-rate limit, N/s: every wrench is checked against it");
  app->add_option("--hand-stiffness", o->dm.hand_stiffness, "N/m");
  app->add_option("--hand-damping", o->dm.hand_damping, "N s/m");
  app->add_flag("--status", o->status, "live one-line status with a progress bar");
}

/// A CSV file t,x,y,z when `name` is a readable file, else a built-in trajectory (throws with
/// the reason on a bad file or an unknown name).
HandTrajectory LoadTrajectory(const std::string& name) {
  std::ifstream f(name);
  if (!f) return HandTrajectory::BuiltIn(name);
  std::stringstream text;
  text << f.rdbuf();
  return HandTrajectory::FromCsv(text.str(), name);
}

/// Makes every `every`-th message bad, one kind in turn; false when this one stays good.
bool InjectBad(int64_t seq, int every, tangent::device_state_t* msg) {
  if (every <= 0 || seq % every != 0) return false;
  switch ((seq / every) % 5) {
    case 0:
      msg->position[0] = NAN;
      break;
    case 1:
      msg->orientation[0] = 0.5;
      break;
    case 2:
      msg->seq = seq - 1;
      break;
    case 3:
      msg->position[1] += 0.03;  // 3 cm in a millisecond, inside the workspace
      break;
    case 4:
      msg->position[1] += 0.5;  // outside the workspace
      break;
  }
  return true;
}

/// What the device loop counted.
struct DriveTotals {
  int64_t sent = 0, sent_live = 0;
  int64_t skipped_periods = 0;  ///< device periods missed while this process was not running
  std::vector<Eigen::Vector3d> forces;  ///< the force applied at each step
};

/// The device loop at `rate` until the duration or a signal: render the last wrench through the
/// driver's watchdog, step the device under the scripted hand, publish its state (and pings).
DriveTotals DriveDevice(const PhantomOptions& o, const HandTrajectory& hand, lcm::LCM* lcm,
                        Receiver* rx, DeviceModel* device,
                        tangent::server::DriverWatchdog* watchdog, int64_t start) {
  std::FILE* log = o.csv_log.empty() ? nullptr : std::fopen(o.csv_log.c_str(), "w");
  if (log) {
    std::fprintf(log,
                 "t,seq,x,y,z,hand_x,hand_y,hand_z,fx,fy,fz,energy,answered_seq,latency_us,"
                 "wrench_state\n");
  }
  DriveTotals totals;
  totals.forces.reserve(static_cast<size_t>(o.duration * o.rate) + 16);
  const double dt = 1.0 / o.rate;
  const int64_t period = static_cast<int64_t>(1e9 / o.rate);
  int64_t next = start, seq = 0, next_ping = start;
  tangent::device_state_t msg{};
  Eigen::Vector3d prev_hand = hand.At(0.0);
  for (int64_t k = 0; !g_stop.load(); ++k) {
    next += period;
    // A device loop that was not run (descheduled, stopped) resumes at its period from now; it
    // never sends the missed states in a burst (they would be stale, and a flood).
    if (const int64_t behind = NowNs() - next; behind > 10 * period) {
      totals.skipped_periods += behind / period;
      next += behind / period * period;
    }
    // Sleep then spin to the deadline (timer slack 1 ns).
    if (next - 200000 > NowNs()) SleepUntil(next - 200000);
    while (NowNs() < next) {
    }
    const double t = 1e-9 * static_cast<double>(NowNs() - start);
    if (t >= o.duration) break;
    LatestWrench w;
    rx->wrench.Read(&w);
    // What a device driver must do (docs/server.md): render the last wrench while wrenches
    // keep coming; when none has come for the watchdog time, ramp the force to zero by itself.
    const Eigen::Vector3d rendered =
        watchdog->Step(t, dt, Eigen::Vector3d(w.force[0], w.force[1], w.force[2]),
                       w.received_ns > 0 ? 1e-9 * static_cast<double>(w.received_ns - start) : -1);
    const Eigen::Vector3d target = hand.At(t);
    const Eigen::Vector3d hand_v = (target - prev_hand) / dt;
    prev_hand = target;
    const Eigen::Vector3d f = device->Step(dt, target, hand_v, rendered);
    totals.forces.push_back(f);
    const bool silent = o.silence_at >= 0 && t >= o.silence_at && t < o.silence_at + o.silence_for;
    if (!silent) {
      msg.utime = NowNs() / 1000;
      msg.device_id = o.device_id;
      msg.session = o.session;
      msg.seq = ++seq;
      for (int i = 0; i < 3; ++i) {
        msg.position[i] = device->position()[i];
        msg.velocity[i] = device->velocity()[i];
      }
      msg.orientation[0] = 1.0;
      msg.orientation[1] = msg.orientation[2] = msg.orientation[3] = 0.0;
      msg.buttons = 1;
      if (!InjectBad(seq, o.inject_bad, &msg)) ++totals.sent_live;
      lcm->publish(o.device_ch, &msg);
      ++totals.sent;
    }
    if (o.ping_rate > 0 && NowNs() >= next_ping) {
      const int64_t now = NowNs();
      lcm->publish(o.ping_ch, &now, sizeof(now));
      next_ping = now + static_cast<int64_t>(1e9 / o.ping_rate);
    }
    if (log) {
      std::fprintf(
          log, "%.4f,%lld,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.4f,%.4f,%.4f,%.6e,%lld,%.1f,%d\n", t,
          static_cast<long long>(msg.seq), device->position()[0], device->position()[1],
          device->position()[2], target[0], target[1], target[2], f[0], f[1], f[2],
          device->energy_from_server(), static_cast<long long>(w.seq), w.latency_us, w.state);
    }
    if (o.status && k % 100 == 0) {
      const int bar = static_cast<int>(30.0 * t / o.duration);
      std::fprintf(stderr,
                   "\r[%-30s] %4.1f/%.0fs  loop %5.0f Hz  contacts %d  |F| %.2f N  answered %zu  ",
                   std::string(static_cast<size_t>(bar), '#').c_str(), t, o.duration,
                   rx->loop_rate.load(), rx->contacts.load(), f.norm(), rx->latency_us.size());
    }
  }
  if (log) std::fclose(log);
  return totals;
}

/// The summary (key=value lines and a verdict line) on stdout.
void PrintSummary(const PhantomOptions& o, const HandTrajectory& hand, const Receiver& rx,
                  const DriveTotals& totals, const DeviceModel& device,
                  const tangent::server::DriverWatchdog& watchdog, int64_t start) {
  const Percentiles lat = Percentiles::Of(rx.latency_us);
  const Percentiles ping = Percentiles::Of(rx.ping_us);
  const int64_t answered = static_cast<int64_t>(rx.answered_seq.size());
  const int64_t lost = std::max<int64_t>(0, totals.sent_live - answered);
  double mean_force = 0.0;
  for (const auto& f : totals.forces) mean_force += f.norm();
  mean_force /= static_cast<double>(std::max<size_t>(1, totals.forces.size()));
  const double roughness = tangent::server::ForceRoughness(totals.forces);
  const double bound = o.dm.max_force * o.dm.max_force / (2.0 * o.coupling_stiffness) + 1e-3;
  const bool passive = device.energy_from_server() <= bound;
  const bool smooth = roughness < 0.05;
  std::printf("tangent-phantom summary (%s, %.1f s at %.0f Hz):\n", hand.name().c_str(), o.duration,
              o.rate);
  std::printf("sent=%lld\nanswered=%lld\nlost=%lld\nlate=%lld\nbad_wrenches=%lld\n",
              static_cast<long long>(totals.sent), static_cast<long long>(answered),
              static_cast<long long>(lost), static_cast<long long>(rx.late),
              static_cast<long long>(rx.bad));
  const int64_t first = rx.first_answer_ns.load();
  std::printf(
      "session=%lld\nfirst_answer_ms=%.3f\ntimeout_wrenches=%lld\nfault_wrenches=%lld\n"
      "foreign_wrenches=%lld\nwatchdog_trips=%lld\n",
      static_cast<long long>(o.session),
      first > 0 ? 1e-6 * static_cast<double>(first - start) : -1.0,
      static_cast<long long>(rx.timeout_wrenches), static_cast<long long>(rx.fault_wrenches),
      static_cast<long long>(rx.foreign), static_cast<long long>(watchdog.trips()));
  std::printf(
      "latency_p50_us=%.1f\nlatency_p99_us=%.1f\nlatency_p999_us=%.1f\nlatency_max_us=%.1f\n",
      lat.p50, lat.p99, lat.p999, lat.max);
  std::printf("ping_p50_us=%.1f\nping_p99_us=%.1f\nping_n=%zu\nlatency_minus_ping_p50_us=%.1f\n",
              ping.p50, ping.p99, ping.n, lat.p50 - ping.p50);
  std::printf("force_mean_n=%.3f\nforce_max_n=%.3f\nforce_roughness_n=%.4f\n", mean_force,
              device.max_applied_force(), roughness);
  std::printf("skipped_periods=%lld\n", static_cast<long long>(totals.skipped_periods));
  std::printf("energy_from_server_j=%.5f\npassivity_bound_j=%.5f\n", device.energy_from_server(),
              bound);
  std::printf(
      "wrench_force_max_n=%.4f\nover_max_force=%lld\nover_rate_limit=%lld\n"
      "worst_rate_excess_n=%.2e\ntimeout_force_rises=%lld\n",
      rx.wrench_force_max, static_cast<long long>(rx.over_max),
      static_cast<long long>(rx.over_rate), rx.worst_rate_excess,
      static_cast<long long>(rx.timeout_force_rises));
  std::printf("loop_rate_hz=%.0f\ncontacts=%d\n", rx.loop_rate.load(), rx.contacts.load());
  const bool stable = passive && smooth && answered > 0;
  std::printf("verdict=%s\n", stable ? "STABLE" : "UNSTABLE");
  std::printf(
      "%s: energy from the server %.2f mJ (bound %.2f mJ: %s), force roughness %.4f N "
      "(%s), round trip p50 %.0f us vs bare LCM ping %.0f us\n",
      stable ? "STABLE" : "UNSTABLE", 1e3 * device.energy_from_server(), 1e3 * bound,
      passive ? "passive" : "NOT passive", roughness, smooth ? "smooth" : "oscillating", lat.p50,
      ping.p50);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tangent-phantom: simulated PHANToM client for tangentd"};
  PhantomOptions o;
  AddOptions(&app, &o);
  CLI11_PARSE(app, argc, argv);

  HandTrajectory hand;
  try {
    hand = LoadTrajectory(o.trajectory);
    hand.LoopFrom(o.loop_from);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tangent-phantom: %s\n", e.what());
    return 2;
  }
  lcm::LCM lcm(o.url);
  if (!lcm.good()) {
    std::fprintf(stderr,
                 "tangent-phantom: LCM could not start on \"%s\" (multicast not routed?). Fix, as "
                 "root: ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo\n",
                 o.url.c_str());
    return 3;
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  if (o.session == 0) {
    std::random_device entropy;  // a nonce, not a simulation input: deliberately unseeded
    o.session = static_cast<int64_t>((static_cast<uint64_t>(entropy()) << 32) | entropy());
  }
  Receiver rx;
  rx.device_id = o.device_id;
  rx.session = o.session;
  rx.late_threshold_us = 1e6 / o.rate;
  rx.max_force = o.dm.max_force;
  rx.max_force_rate = o.max_force_rate;
  rx.latency_us.reserve(static_cast<size_t>(o.duration * o.rate * 1.1) + 16);
  rx.answered_seq.reserve(rx.latency_us.capacity());
  tangent::server::LcmSubscriptions subs(&lcm);
  subs.Typed<tangent::wrench_t>(o.wrench_ch,
                                [&rx](const tangent::wrench_t& m) { rx.OnWrench(&m); });
  subs.Raw(o.pong_ch, [&rx](const void* data, uint32_t size) { rx.OnPong(data, size); });
  subs.Typed<tangent::loop_stats_t>(o.stats_ch,
                                    [&rx](const tangent::loop_stats_t& m) { rx.OnStats(&m); });
  std::atomic<bool> rx_stop{false};
  std::thread rx_thread([&] {
    while (!rx_stop.load()) lcm.handleTimeout(5);
  });

  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  DeviceModel device(o.dm);
  tangent::server::DriverWatchdog watchdog(1e-3 * o.watchdog_ms, o.watchdog_rate);
  const int64_t start = NowNs();
  // The same instant on the wall clock: what scripts align their own timestamps with (the log's
  // t counts from here, however late a loaded machine started this process).
  const double start_unix =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const DriveTotals totals = DriveDevice(o, hand, &lcm, &rx, &device, &watchdog, start);
  // Let the last answers arrive.
  SleepUntil(NowNs() + 50000000LL);
  rx_stop.store(true);
  rx_thread.join();
  if (o.status) std::fprintf(stderr, "\n");
  std::printf("start_unix=%.6f\n", start_unix);
  PrintSummary(o, hand, rx, totals, device, watchdog, start);
  return 0;
}
