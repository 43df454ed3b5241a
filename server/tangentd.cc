// tangentd: the haptic server. Loads a scene, runs the servo loop (one core), the global contact
// stage (the other core) and the LCM bridge, until SIGINT/SIGTERM or --duration. Prints the load
// log, then (with --status) a one-line status per second, and a key=value summary at exit.

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "server/bridge.h"
#include "server/engine.h"
#include "server/scene.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }
/// --fault-injection: SIGUSR1 stalls the global stage once (scripts/faults.sh). Set before the
/// handler is installed and cleared after it is removed; the handler only stores an atomic.
std::atomic<tangent::server::Engine*> g_engine{nullptr};
/// A --device-id value that is a whole 64-bit integer, else nullopt.
std::optional<int64_t> ParseDeviceId(const std::string& v) {
  if (v.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long long id = std::strtoll(v.c_str(), &end, 10);
  if (errno != 0 || *end != '\0') return std::nullopt;
  return static_cast<int64_t>(id);
}
void OnStallSignal(int) {
  if (tangent::server::Engine* e = g_engine.load()) e->InjectGlobalStall();
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tangent::server;
  CLI::App app{"tangentd: haptic-rate manipulation of NURBS parts over LCM"};
  std::string scene_path, log_path, url = kDefaultLcmUrl;
  EngineOptions eo;
  Channels ch;
  double duration = 0.0;
  bool status = false;
  BridgeOptions bo;
  std::string device_id;
  app.add_option("--scene", scene_path, "scene file (JSON)")->required()->check(CLI::ExistingFile);
  app.add_option("--rate", eo.rate_hz, "servo loop rate, Hz")->check(CLI::Range(100.0, 50000.0));
  app.add_option("--spin-us", eo.spin_us, "spin this long before each deadline, us")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--servo-cpu", eo.servo_cpu, "core for the servo loop (-1: any)");
  app.add_option("--global-cpu", eo.global_cpu, "core for the global contact stage (-1: any)");
  app.add_option("--dof", eo.servo.dof, "device mode: 3 (force) or 6 (force and torque)")
      ->check(CLI::IsMember({3, 6}));
  app.add_option("--timeout", eo.servo.device_timeout,
                 "device silence before the force ramps "
                 "to zero, s")
      ->check(CLI::Range(0.001, 10.0));
  app.add_option("--iterations", eo.servo.max_iterations, "solver iterations per tick")
      ->check(CLI::Range(1, 100));
  app.add_option("--max-part-speed", eo.servo.max_part_speed,
                 "fastest a part near a pitchfork of a contact's distance moves in a tick's "
                 "solve, m/s (0: no bound)")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--lcm-url", url, "LCM URL (default: multicast with ttl=0 on a private group)");
  app.add_option("--view-lcm-url", bo.view_url,
                 "LCM URL for viewers: scene, contacts, statistics, and the last wrench and "
                 "device state at about 30 Hz (\"\": none)");
  app.add_option("--device-channel", ch.device, "channel of device_state_t");
  app.add_option("--wrench-channel", ch.wrench, "channel of wrench_t");
  app.add_option("--contacts-channel", ch.contacts, "channel of contact_states_t");
  app.add_option("--stats-channel", ch.stats, "channel of loop_stats_t");
  app.add_option("--scene-channel", ch.scene, "channel of scene_state_t");
  app.add_option("--device-id", device_id,
                 "the device served (device_state_t.device_id; default: the scene's device.id), "
                 "or \"any\": the first device that earns a session")
      ->check([](const std::string& v) -> std::string {
        return ParseDeviceId(v) || v == "any"
                   ? ""
                   : "must be an integer (a device_state_t.device_id) or \"any\", "
                     "got \"" +
                         v + "\"";
      });
  app.add_option("--stats-rate", bo.stats_rate_hz, "loop_stats_t messages per second")
      ->check(CLI::Range(0.1, 100.0));
  app.add_option("--log", log_path, "log file (load log and one status line per second)");
  app.add_option("--duration", duration, "stop after this many seconds (0: run until a signal)");
  app.add_flag("--status", status, "print a live status line");
  bool fault_injection = false;
  app.add_flag("--fault-injection", fault_injection,
               "testing only: SIGUSR1 stalls the global contact stage once for 100 ms");
  CLI11_PARSE(app, argc, argv);

  bo.device_id = ParseDeviceId(device_id);
  bo.any_device = device_id == "any";
  std::FILE* log = nullptr;
  if (!log_path.empty()) {
    log = std::fopen(log_path.c_str(), "w");
    if (!log) {
      std::fprintf(stderr, "tangentd: cannot write the log file %s\n", log_path.c_str());
      return 2;
    }
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  try {
    std::unique_ptr<Scene> scene = LoadScene(scene_path);
    for (const std::string& line : scene->load_log) {
      std::printf("load: %s\n", line.c_str());
      if (log) std::fprintf(log, "load: %s\n", line.c_str());
    }
    Engine engine(*scene, eo);
    Bridge bridge(&engine, url, ch, log, status, bo);
    std::printf(
        "tangentd: scene \"%s\": %d bodies, %zu surfaces, %zu contact pairs, %zu body pairs, "
        "%d contacts at rest, %d clearance trees; %.0f Hz, %d-DOF device, LCM %s, viewers on %s\n",
        scene->name.c_str(), scene->mechanism.num_bodies(), scene->surfaces.size(),
        scene->pairs.size(), scene->body_pairs.size(), engine.servo().active_contacts(),
        engine.clearance_trees(), eo.rate_hz, eo.servo.dof, url.c_str(),
        bo.view_url.empty() ? "(none)" : bo.view_url.c_str());
    const std::string serving = bridge.Serving();
    std::printf("tangentd: %s\n", serving.c_str());
    if (log) std::fprintf(log, "%s\n", serving.c_str());
    std::fflush(stdout);
    engine.Start();
    if (fault_injection) {
      g_engine.store(&engine);
      std::signal(SIGUSR1, OnStallSignal);
    }
    // The bridge (this thread) keeps off the servo's core: it shares the global stage's.
    PinToCore(eo.global_cpu);
    bridge.Run(g_stop, duration);
    if (fault_injection) {
      std::signal(SIGUSR1, SIG_IGN);
      g_engine.store(nullptr);
    }
    engine.Stop();
    std::printf("tangentd summary:\n%s", bridge.Report().c_str());
    if (log) std::fprintf(log, "summary:\n%s", bridge.Report().c_str());
  } catch (const SceneError& e) {
    std::fprintf(stderr, "tangentd: scene error: %s\n", e.what());
    return 2;
  } catch (const LcmError& e) {
    std::fprintf(stderr, "tangentd: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tangentd: %s\n", e.what());
    return 1;
  }
  if (log) std::fclose(log);
  return 0;
}
