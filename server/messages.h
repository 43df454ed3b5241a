#pragma once

// The plain-data messages that cross threads inside tangentd (servo, global stage, LCM bridge)
// and their conversions. Plain data only (trivially copyable, fixed size): they travel through
// seqlocks and SPSC rings (lockfree.h) and carry no pointers into any thread's state.

#include <cstdint>
#include <vector>

#include "contact/global.h"

namespace tangent::server {

inline constexpr int kMaxBodies = 32;
inline constexpr int kMaxContacts = 32;

/// A device state the LCM bridge accepted (plain data: it crosses threads in a Seqlock).
struct DeviceSample {
  int64_t utime = 0;      ///< client clock, µs (echoed, never used for timing)
  int64_t device_id = 0;  ///< echoed
  int64_t session = 0;    ///< echoed
  int64_t seq = 0;        ///< echoed
  /// Sessions started so far at the bridge (DeviceFilter::session_index): when it changes, the
  /// servo starts the new session's coupling afresh (force from zero, a new ramp).
  int64_t session_index = 0;
  /// Index of this state among all accepted ones (1, 2, ...): gaps between the states the
  /// servo answers are accepted states it never answered.
  int64_t accepted = 0;
  double position[3] = {0, 0, 0};        ///< device frame, m
  double orientation[4] = {1, 0, 0, 0};  ///< device frame, (w, x, y, z)
  double velocity[3] = {0, 0, 0};        ///< device frame, m/s
  int32_t buttons = 0;
  int64_t received_ns = 0;  ///< server CLOCK_MONOTONIC at receipt
};

/// A contact the servo tracks (plain data, for the snapshot).
struct TrackedContact {
  int32_t surface_a = 0, surface_b = 0, body_a = 0, body_b = 0;
  double u[4] = {0, 0, 0, 0};
  double beta = 0.0;
  double p_a[3] = {0, 0, 0}, p_b[3] = {0, 0, 0};
  double force = 0.0;  ///< multiplier, N
  /// contact::TrimmedForm: 0 the faces, 1 or 2 a trim edge of one surface against the other's
  /// face, 3 edge against edge (trimmed pairs only).
  int32_t form = 0;
};

/// Servo → global stage and LCM bridge: the configuration and the tracked contacts.
struct Snapshot {
  int64_t tick = 0;
  int32_t num_bodies = 0;
  double q[kMaxBodies][7] = {};
  int32_t num_contacts = 0;
  TrackedContact contacts[kMaxContacts] = {};
  double grasp_target[3] = {0, 0, 0};
  int64_t events_taken = 0;  ///< contact events the servo has taken (applied or dropped)
};

/// The body pairs a scene may watch at most (each pair of kMaxBodies bodies).
inline constexpr int kMaxBodyPairs = kMaxBodies * (kMaxBodies - 1) / 2;

/// Global stage → servo: a clearance certificate (contact::ClearanceCertifier) for the body pairs
/// the stage watches, in contact::WatchedBodyPairs order, and the poses it holds at: the servo
/// keeps every step within it (optimizer::ClearanceGuard).
struct ClearanceMsg {
  int64_t tick = 0;  ///< the snapshot's
  int32_t num_bodies = 0, num_pairs = 0;
  double q[kMaxBodies][7] = {};
  double clearance[kMaxBodyPairs] = {};  ///< m; +∞: not certified (in contact, or touching)
};

/// Global stage → servo: one contact event (plain data, for the SPSC ring).
struct ContactEventMsg {
  int32_t added = 1;  ///< 1 added, 0 removed
  int32_t surface_a = 0, surface_b = 0;
  double u[4] = {0, 0, 0, 0};
};

/// Wrench states (wrench_t.state).
enum WrenchState : int8_t { kRunning = 0, kRampingUp = 1, kTimeout = 2, kFault = 3 };

/// The wrench of one tick, device frame (plain data, for the SPSC ring to the bridge).
struct WrenchSample {
  int64_t utime = 0, seq = 0;          ///< echo of the device sample answered
  int64_t device_id = 0, session = 0;  ///< echo of the device sample answered
  int64_t server_utime = 0;
  int64_t received_ns = 0;  ///< the device sample's receipt (bridge), CLOCK_MONOTONIC
  int64_t tick_start_ns = 0, tick_end_ns = 0;  ///< the answering tick (tick_end_ns: engine)
  double force[3] = {0, 0, 0};                 ///< N
  double torque[3] = {0, 0, 0};                ///< N m
  int8_t state = kRunning;                     ///< WrenchState
};

/// A global-stage event as the servo takes it.
ContactEventMsg ToEventMsg(const contact::ContactEvent& e);
/// The global stage's inputs from a snapshot: body poses and the tracked contacts.
void ToGlobalInput(const Snapshot& s, std::vector<contact::BodyPose>* poses,
                   std::vector<contact::GlobalContact>* tracked);

}  // namespace tangent::server
