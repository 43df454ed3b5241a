#pragma once

// Which device states the server applies (issue 12, docs/server.md "Device sessions" and "Sane
// states only"). The gate in front of the servo's mailbox, run by the LCM bridge:
//   1. device id: the server serves the device the scene or --device-id declares; states of any
//      other device are rejected, whoever spoke first. With none declared nothing is served,
//      unless the deliberate choice "any" was made (the first device to earn a session);
//   2. session: while the owner is live (an accepted state within owner_timeout), a state of a
//      session it took over is stale and rejected; gaps in the served session's sequence
//      numbers are counted as states lost before the server, up to what a session could have
//      sent since it began (beyond that, a reset of its numbering: counted, not lost);
//   3. content: a NaN or infinite field, an orientation that is not a unit quaternion, a
//      position outside the device's workspace box (device frame) are rejected;
//   4. a session that is not served earns the device: takeover_states consecutive sane states,
//      none further than a hand moves from the current grasp point, none more than
//      takeover_gap after the last; it is served from the last of them on (the servo starts a
//      fresh force ramp for it). A live owner is taken over at most once per
//      takeover_interval; a silent one (owner_timeout) is free to take, by its own earlier
//      session or any other of the device;
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
  /// The device served. With none (and any_device false) no device is served: every state is
  /// rejected as kDeviceId, and tangentd says so at start-up.
  std::optional<int64_t> device_id;
  /// The deliberate choice to serve the first device that earns a session (tangentd
  /// --device-id any); it is then the only one served.
  bool any_device = false;
  double quaternion_tolerance = 1e-3;  ///< | |Q| − 1 | allowed
  /// Workspace box, device frame, m: positions outside are rejected. Default: a Touch-class
  /// stylus (kTouchWorkspace). Scenes set their device's box (docs/server.md).
  double workspace_min[3] = {-kTouchWorkspace[0], -kTouchWorkspace[1], -kTouchWorkspace[2]};
  double workspace_max[3] = {kTouchWorkspace[0], kTouchWorkspace[1], kTouchWorkspace[2]};
  double max_speed = 5.0;         ///< m/s: faster than a hand moves a stylus
  double min_jump = 0.01;         ///< m: jumps below this are never implausible
  double reacquire_after = 0.25;  ///< s of silence (server clock) after which a jump is allowed
  // Earning the device (a new session, a restart, a takeover, a return after the owner's silence).
  int takeover_states = 20;        ///< consecutive sane states before a session is served
  double takeover_gap = 0.05;      ///< s: a longer gap between two of them starts the count again
  double takeover_interval = 0.5;  ///< s: a live owner is taken over at most this often
  double owner_timeout = 0.1;      ///< s without an accepted state: the owner is silent (servo's)
  // How many states may be counted lost (a token bucket): seq_slack at the session's start,
  // refilled at max_state_rate per second (100 × a 1 kHz device: the fastest flood the suite
  // sends), holding at most seq_slack + one second of it. A gap beyond what the bucket holds
  // was never sent: a reset of the numbering, counted as such.
  double max_state_rate = 1e5;
  double seq_slack = 1000.0;
};

struct DeviceFilterCounts {
  int64_t accepted = 0;
  int64_t sessions = 0;    ///< sessions started (the first, and each takeover)
  int64_t lost = 0;        ///< gaps in the served session's sequence numbers
  int64_t seq_resets = 0;  ///< jumps in seq beyond what the session could have sent (not lost)
  int64_t non_finite = 0;
  int64_t quaternion = 0;
  int64_t workspace = 0;
  int64_t device = 0;   ///< another device id
  int64_t session = 0;  ///< a stale (taken-over) session
  int64_t sequence = 0;
  int64_t jump = 0;
  int64_t pending = 0;  ///< sane states of a session earning the device (not yet served)
  int64_t rejected() const {
    return non_finite + quaternion + workspace + device + session + sequence + jump + pending;
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
    kJump,
    kPending  ///< sane, of a session earning the device: counted towards its takeover
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
  /// Whether a device is declared or the "any" choice made (else nothing is ever served).
  bool serves_a_device() const { return device_.has_value() || o_.any_device; }

 private:
  /// A session earning the device: its streak of consecutive sane states.
  struct Candidate {
    int64_t device_id = 0;
    int64_t session = 0;
    int64_t last_seq = 0;
    int64_t last_ns = 0;
    int streak = 0;  ///< 0: a free slot
  };
  Verdict Judge(const DeviceReading& m, int64_t received_ns);
  /// A sane state of a session that is not served: rejected or counted towards its takeover.
  Verdict Earn(const DeviceReading& m, int64_t received_ns, bool owner_live);
  /// Counts the served session's sequence gaps (lost, or a reset when implausible).
  void CountSequence(const DeviceReading& m, int64_t received_ns);
  bool Served(int64_t device_id) const { return device_ ? device_id == *device_ : o_.any_device; }
  bool Retired(int64_t session) const;
  void Retire(int64_t session);
  static int64_t Ns(double seconds) { return static_cast<int64_t>(seconds * 1e9); }

  DeviceFilterOptions o_;
  DeviceFilterCounts counts_;
  std::optional<int64_t> device_;  ///< the device served
  bool have_session_ = false;
  int64_t session_ = 0;
  int64_t highest_seq_ = 0;   ///< highest seq seen in the served session (for gaps)
  double lost_budget_ = 0.0;  ///< states that may still be counted lost (the bucket)
  int64_t budget_ns_ = 0;     ///< when it was last refilled
  int64_t last_seq_ = 0;      ///< last accepted seq
  int64_t last_ns_ = 0;       ///< receipt of the last accepted state
  double last_p_[3] = {0, 0, 0};
  /// Sessions taken over (a ring: the last kRetired; older ones are long gone from the network).
  static constexpr int kRetired = 64;
  int64_t retired_[kRetired] = {};
  int retired_count_ = 0;
  static constexpr int kCandidates = 16;
  Candidate candidates_[kCandidates];
  int64_t last_takeover_ns_ = 0;
  bool any_takeover_ = false;
};

}  // namespace tangent::server
