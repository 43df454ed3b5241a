// libFuzzer target: the server's whole device-message path without sockets — the bridge's
// packet decode and device filter (server/lcm_convert.h ReadDevicePacket) and the servo's ticks
// (ServoLoop::Tick) on the floating-contact four-bar — driven by a byte script of packets and
// server-clock time. Each input gets a fresh filter and servo, so a finding replays exactly.
//
// Script: records, each an op byte and its operands (a record cut short by the end is dropped):
//   op % 4 == 0  raw packet: a length byte n, then n bytes (LCM's own encoding: mutations of
//                the seed corpus reach the filter; others test the decoder)
//   op % 4 == 1  a device state built from fields (encoded, then the same path): device id,
//                session, seq step, position (int16 × 10 µm, or raw doubles when op & 4),
//                orientation (a small rotation, or raw doubles when op & 8), velocity (raw when
//                op & 16), buttons
//   op % 4 == 2  n ticks of 250 µs (a byte n): the servo at 4 kHz through silences
//   op % 4 == 3  one tick after a gap of n × 50 µs: a late or early servo
// Every packet is followed by one 250 µs tick. Every wrench the servo sends is checked against
// the safety contract (docs/server.md "Safety"): force and torque finite, |F| ≤ max_force,
// |ΔF| ≤ max_force_rate × min(server time since the last wrench, two device periods) within a
// session, and within a session the answered states' sequence numbers strictly increase (never
// a stale state applied). A violation aborts.
// TANGENT_FUZZ_TRACE=1 prints every wrench (replaying a finding).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

#include <tangent/device_state_t.hpp>

#include "server/device_filter.h"
#include "server/lcm_convert.h"
#include "server/scene.h"
#include "server/servo.h"

namespace {

using tangent::server::DeviceFilter;
using tangent::server::DeviceFilterOptions;
using tangent::server::DeviceSample;
using tangent::server::PacketFate;
using tangent::server::Scene;
using tangent::server::ServoLoop;
using tangent::server::ServoOptions;
using tangent::server::TickResult;
using tangent::server::WrenchSample;

constexpr int64_t kTick = 250'000;   // ns: the servo at 4 kHz
constexpr int64_t kMaxTicks = 1000;  // per input (an input costs its ticks)
constexpr int64_t kSessions[4] = {0x5eed, 0x5eed + 1, -7, INT64_MAX};

const Scene& TheScene() {
  static const std::unique_ptr<Scene> scene =
      tangent::server::LoadScene(std::string(TANGENT_SCENES_DIR) + "/fourbar_point.json");
  return *scene;
}

[[noreturn]] void Finding(const char* what, double value) {
  std::fprintf(stderr, "device_fuzzer: %s (%.17g)\n", what, value);
  std::abort();
}

/// Reads the script's bytes; past the end every read fails.
struct Reader {
  const uint8_t* p;
  size_t n;
  bool Take(void* out, size_t k) {
    if (k > n) return false;
    std::memcpy(out, p, k);
    p += k;
    n -= k;
    return true;
  }
  bool Byte(uint8_t* b) { return Take(b, 1); }
};

struct Rig {
  const Scene& scene = TheScene();
  DeviceFilter filter;
  ServoLoop servo{scene, ServoOptions{}};
  tangent::device_state_t scratch{};
  DeviceSample sample;
  bool have_sample = false;
  TickResult r;
  int64_t now = 1'000'000'000;
  int64_t ticks = 0;
  int64_t seq = 0;
  WrenchSample last;
  bool have_last = false;
  int64_t last_session = 0, last_seq = 0;
  bool have_answer = false;

  explicit Rig(const DeviceFilterOptions& o) : filter(o) {}

  void Packet(const void* data, uint32_t size) {
    bool wrong_type = false;
    DeviceSample s;
    if (tangent::server::ReadDevicePacket(data, size, now, &filter, &scratch, &s, &wrong_type) ==
        PacketFate::kAccepted) {
      sample = s;
      have_sample = true;
    }
    Tick(kTick);
  }

  void Tick(int64_t gap) {
    if (ticks >= kMaxTicks) return;
    ++ticks;
    now += gap;
    servo.Tick(have_sample ? &sample : nullptr, now, &r);
    if (r.answered) Check(r.wrench);
  }

  void Check(const WrenchSample& w) {
    static const bool trace = std::getenv("TANGENT_FUZZ_TRACE") != nullptr;
    if (trace) {
      std::fprintf(stderr, "wrench t=%lld us seq %lld state %d F=(%.6f %.6f %.6f)\n",
                   static_cast<long long>(w.server_utime), static_cast<long long>(w.seq), w.state,
                   w.force[0], w.force[1], w.force[2]);
    }
    const tangent::server::DeviceSpec& d = scene.device;
    double f2 = 0.0, step2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(w.force[i]) || !std::isfinite(w.torque[i]))
        Finding("non-finite wrench", w.force[i]);
      f2 += w.force[i] * w.force[i];
      if (have_last) step2 += (w.force[i] - last.force[i]) * (w.force[i] - last.force[i]);
    }
    if (std::sqrt(f2) > d.max_force + 1e-9) Finding("force above max_force", std::sqrt(f2));
    if (have_last && w.session == last.session) {
      // server_utime is the tick's clock in whole µs: one µs of rounding each side. The cap:
      // a late wrench steps no further than two device periods' worth. (A new session starts
      // from zero: its driver restarted, docs/server.md "Device sessions".)
      const double dt = std::min(1e-6 * static_cast<double>(w.server_utime - last.server_utime),
                                 2.0 / d.device_rate) +
                        2e-6;
      if (std::sqrt(step2) > d.max_force_rate * dt + 1e-9)
        Finding("force step beyond the rate limit", std::sqrt(step2));
    }
    if (w.state != tangent::server::kTimeout) {
      if (have_answer && w.session == last_session && w.seq <= last_seq)
        Finding("a state answered out of order", static_cast<double>(w.seq));
      have_answer = true;
      last_session = w.session;
      last_seq = w.seq;
    }
    last = w;
    have_last = true;
  }
};

double Raw(Reader* in) {
  double x = 0.0;
  in->Take(&x, sizeof x);
  return x;
}

bool StructuredState(uint8_t op, Reader* in, Rig* rig) {
  uint8_t id = 0, session = 0, buttons = 0;
  int8_t step = 0;
  if (!in->Byte(&id) || !in->Byte(&session) || !in->Take(&step, 1) || !in->Byte(&buttons))
    return false;
  tangent::device_state_t m{};
  m.device_id = id & 3;
  m.session = kSessions[session & 3];
  rig->seq += step;
  m.seq = rig->seq;
  m.utime = rig->now / 1000;
  m.buttons = buttons;
  for (int i = 0; i < 3; ++i) {
    if (op & 4) {
      m.position[i] = Raw(in);
    } else {
      int16_t x = 0;
      if (!in->Take(&x, 2)) return false;
      m.position[i] = 1e-5 * x;
    }
  }
  if (op & 8) {
    for (double& q : m.orientation) q = Raw(in);
  } else {
    uint8_t a = 0;
    if (!in->Byte(&a)) return false;
    const double half = 0.01 * (a - 128);  // a turn about a tilted axis
    m.orientation[0] = std::cos(half);
    m.orientation[1] = 0.6 * std::sin(half);
    m.orientation[3] = 0.8 * std::sin(half);
  }
  if (op & 16) {
    for (double& v : m.velocity) v = Raw(in);
  }
  uint8_t buf[256];
  const int size = m.encode(buf, 0, sizeof buf);
  if (size < 0) std::abort();
  rig->Packet(buf, static_cast<uint32_t>(size));
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  DeviceFilterOptions o;
  // The first device to earn a session (ids 0..3 come from the input), after 3 steady states
  // rather than 20: short inputs then reach takeovers, returns and stale sessions. (The rule's
  // own count and timing are DeviceFilterTest's.)
  o.any_device = true;
  o.takeover_states = 3;
  const Scene& scene = TheScene();
  for (int i = 0; i < 3; ++i) {
    o.workspace_min[i] = scene.device.workspace_min[i];
    o.workspace_max[i] = scene.device.workspace_max[i];
  }
  Rig rig(o);
  Reader in{data, size};
  uint8_t op = 0;
  while (in.Byte(&op) && rig.ticks < kMaxTicks) {
    uint8_t n = 0;
    switch (op & 3) {
      case 0: {
        uint8_t buf[256];
        if (!in.Byte(&n) || !in.Take(buf, n)) return 0;
        rig.Packet(buf, n);
        break;
      }
      case 1:
        if (!StructuredState(op, &in, &rig)) return 0;
        break;
      case 2:
        if (!in.Byte(&n)) return 0;
        for (int k = 0; k < n; ++k) rig.Tick(kTick);
        break;
      default:
        if (!in.Byte(&n)) return 0;
        rig.Tick(50'000 * static_cast<int64_t>(n));
        break;
    }
  }
  return 0;
}
