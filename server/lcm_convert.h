#pragma once

// Conversions between the LCM messages (msgs/) and the server's plain-data messages
// (messages.h): pure functions, testable without sockets (tests/server/lcm_convert_test.cc).
// The bridge calls nothing else to fill or read a message.

#include <cstdint>

#include <tangent/contact_states_t.hpp>
#include <tangent/device_state_t.hpp>
#include <tangent/scene_state_t.hpp>
#include <tangent/wrench_t.hpp>

#include "server/device_filter.h"
#include "server/messages.h"
#include "server/scene.h"

namespace tangent::server {

/// What the device filter judges of a device state.
DeviceReading ToReading(const tangent::device_state_t& m);
/// An accepted device state as the servo takes it: `session_index` and `accepted` from the
/// filter, `received_ns` the server's receipt time.
DeviceSample ToSample(const tangent::device_state_t& m, int64_t session_index, int64_t accepted,
                      int64_t received_ns);
/// What became of one packet on the device channel.
enum class PacketFate {
  kUndecodable,  ///< not a device_state_t (counted; `wrong_type` if another Tangent message)
  kRejected,     ///< decoded, refused by the filter (counted there by reason)
  kAccepted,     ///< decoded and accepted: `sample` is what the servo takes
};

/// The bridge's whole path for one device-channel packet, without sockets: decodes `data` into
/// `scratch` (its storage reused), judges it with `filter` as received at `received_ns` (server
/// clock) and, when accepted, fills `sample`. `*wrong_type` says whether an undecodable packet
/// carries another Tangent type's fingerprint. Allocates nothing; any bytes are safe.
PacketFate ReadDevicePacket(const void* data, uint32_t size, int64_t received_ns,
                            DeviceFilter* filter, tangent::device_state_t* scratch,
                            DeviceSample* sample, bool* wrong_type);

/// A tick's wrench as published (device frame); echoes the answered state's ids.
void ToWrenchMsg(const WrenchSample& w, tangent::wrench_t* out);
/// The tracked contacts of a snapshot; `utime` the server's clock (µs). Reuses out's storage.
void ToContactStates(const Snapshot& snap, int64_t utime, tangent::contact_states_t* out);
/// The bodies' poses of a snapshot with their scene names. Reuses out's storage.
void ToSceneState(const Snapshot& snap, const Scene& scene, int64_t utime,
                  tangent::scene_state_t* out);

}  // namespace tangent::server
