#pragma once

// Which device states the server applies (issue 12, docs/server.md "Device sessions" and "Sane
// states only"). The gate in front of the servo's mailbox, run by the LCM bridge:
//   1. device id: the server serves one device (configured, or the first whose state is
//      accepted); states of any other device are rejected;
//   2. session: a state of a session that was taken over is stale and rejected; gaps in the
//      served session's sequence numbers are counted as states lost before the server;
//   3. content: a NaN or infinite field, an orientation that is not a unit quaternion, a
//      position outside the device's workspace box (device frame) are rejected;
//   4. a state of a session not seen before, with sane content, takes over at once (a
//      restarted client, seq from 1): the servo starts a fresh force ramp for it;
//   5. in the served session: a sequence number not above the last accepted, or a jump faster
//      than a hand moves a stylus (on the server's clock), is rejected.
// Every rejection is counted by reason; a rejected state never changes the scene. Times are the
// server's (CLOCK_MONOTONIC at receipt): the client's utime is echoed, never trusted.

#include <cstdint>
#include <optional>

namespace tangent::server {

/// Half extents of the default workspace box, device frame, m: a Touch-class stylus (160 × 120
/// × 70 mm, DeviceModelOptions::workspace) with 25 % margin per side for calibration offsets.
inline constexpr double kTouchWorkspace[3] = {0.1, 0.075, 0.045};

/// A device state as received (plain data; the bridge copies the LCM message into it).
struct DeviceReading {
  int64_t device_id = 0;
  int64_t session = 0;
  int64_t utime = 0;  ///< client clock, µs (echoed only)
  int64_t seq = 0;
  double position[3] = {0, 0, 0};        ///< device frame, m
  double orientation[4] = {1, 0, 0, 0};  ///< device frame, (w, x, y, z)
  double velocity[3] = {0, 0, 0};        ///< device frame, m/s
};

struct DeviceFilterOptions {
  /// The device served (nullopt: the first device whose state is accepted).
  std::optional<int64_t> device_id;
  double quaternion_tolerance = 1e-3;  ///< | |Q| − 1 | allowed
  /// Workspace box, device frame, m: positions outside are rejected. Default: a Touch-class
  /// stylus (kTouchWorkspace). Scenes set their device's box (docs/server.md).
  double workspace_min[3] = {-kTouchWorkspace[0], -kTouchWorkspace[1], -kTouchWorkspace[2]};
  double workspace_max[3] = {kTouchWorkspace[0], kTouchWorkspace[1], kTouchWorkspace[2]};
  double max_speed = 5.0;         ///< m/s: faster than a hand moves a stylus
  double min_jump = 0.01;         ///< m: jumps below this are never implausible
  double reacquire_after = 0.25;  ///< s of silence (server clock) after which a jump is allowed
};

struct DeviceFilterCounts {
  int64_t accepted = 0;
  int64_t sessions = 0;  ///< sessions started (the first, and each takeover)
  int64_t lost = 0;      ///< gaps in the served session's sequence numbers
  int64_t non_finite = 0;
  int64_t quaternion = 0;
  int64_t workspace = 0;
  int64_t device = 0;   ///< another device id
  int64_t session = 0;  ///< a stale (taken-over) session
  int64_t sequence = 0;
  int64_t jump = 0;
  int64_t rejected() const {
    return non_finite + quaternion + workspace + device + session + sequence + jump;
  }
};

class DeviceFilter {
 public:
  enum class Verdict {
    kAccepted,
    kNewSession,  ///< accepted, and its session took over (the servo ramps afresh)
    kNonFinite,
    kQuaternion,
    kWorkspace,
    kDeviceId,
    kStaleSession,
    kSequence,
    kJump
  };
  explicit DeviceFilter(const DeviceFilterOptions& o = {});

  /// Judges one state received at `received_ns` (server CLOCK_MONOTONIC) and counts it.
  Verdict Check(const DeviceReading& m, int64_t received_ns);
  static bool Accepted(Verdict v) { return v == Verdict::kAccepted || v == Verdict::kNewSession; }

  const DeviceFilterCounts& counts() const { return counts_; }
  /// Sessions started so far (1 for the first): the servo resets its coupling when it changes.
  int64_t session_index() const { return counts_.sessions; }
  const DeviceFilterOptions& options() const { return o_; }
  static const char* ToString(Verdict v);

 private:
  Verdict Judge(const DeviceReading& m, int64_t received_ns);
  bool Retired(int64_t session) const;
  void Retire(int64_t session);

  DeviceFilterOptions o_;
  DeviceFilterCounts counts_;
  std::optional<int64_t> device_;  ///< the device served
  bool have_session_ = false;
  int64_t session_ = 0;
  int64_t highest_seq_ = 0;  ///< highest seq seen in the served session (for gaps)
  int64_t last_seq_ = 0;     ///< last accepted seq
  int64_t last_ns_ = 0;      ///< receipt of the last accepted state
  double last_p_[3] = {0, 0, 0};
  /// Sessions taken over (a ring: the last kRetired; older ones are long gone from the network).
  static constexpr int kRetired = 64;
  int64_t retired_[kRetired] = {};
  int retired_count_ = 0;
};

}  // namespace tangent::server
