#pragma once

// The LCM bridge thread (issue 6): device states in (validated, into the servo's mailbox),
// wrenches out (as soon as the servo signals one), contacts and scene poses for viewers, loop
// statistics once per second, and a bare ping-pong responder for latency baselines.

#include <atomic>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "server/device_filter.h"
#include "server/engine.h"

namespace lcm {
class LCM;
}

namespace tangent::server {

struct Channels {
  std::string device = "TANGENT_DEVICE";
  std::string wrench = "TANGENT_WRENCH";
  std::string contacts = "TANGENT_CONTACTS";
  std::string stats = "TANGENT_STATS";
  std::string scene = "TANGENT_SCENE";
  std::string ping = "TANGENT_PING";  ///< echoed at once on `pong` (bare round-trip baseline)
  std::string pong = "TANGENT_PONG";
};

/// Multicast on a non-default group with ttl=0: traffic stays on this host.
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.68:7668?ttl=0";
/// Where viewers listen (tangent-view, docs/viewer.md): the same group on another port, so a
/// viewer never receives the kilohertz device and wrench traffic. On loopback multicast every
/// packet is copied to every member socket inside the sender's own send call, so a viewer on
/// the main URL would put its wake-ups into the servo's round trip.
inline constexpr const char* kDefaultViewLcmUrl = "udpm://239.255.76.68:7669?ttl=0";

/// LCM could not start; the message says why and how to fix it.
class LcmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Creates an LCM instance or throws LcmError with the exact fix when multicast is not routed.
std::unique_ptr<lcm::LCM> OpenLcm(const std::string& url);

struct BridgeSummary {
  DeviceFilterCounts filter;
  int64_t undecodable = 0;  ///< packets on the device channel that are not a device_state_t
  int64_t wrong_type = 0;   ///< ... of which another Tangent message type (by fingerprint)
  int64_t wrenches_sent = 0;
  int64_t pings = 0;
};

struct BridgeOptions {
  /// The device served, overriding the scene's device.id (docs/server.md "Device sessions").
  std::optional<int64_t> device_id;
  /// With no device declared (here or in the scene): serve the first device that earns a
  /// session (tangentd --device-id any). Without it, such a server serves nothing.
  bool any_device = false;
  double stats_rate_hz = 1.0;  ///< loop_stats_t messages per second
  /// Viewers' LCM URL (empty: none): the scene, contacts and statistics, and at the scene's
  /// rate (about 30 Hz) the last wrench sent and the last device state accepted, on the same
  /// channel names as the main URL (which carries all of these too).
  std::string view_url = kDefaultViewLcmUrl;
};

class Bridge {
 public:
  Bridge(Engine* engine, const std::string& url, const Channels& channels, std::FILE* log,
         bool status_line, const BridgeOptions& options = {});
  ~Bridge();
  /// Runs until *stop (checked every 10 ms) or `duration_s` (> 0) has passed.
  void Run(const std::atomic<bool>& stop, double duration_s);
  const BridgeSummary& summary() const { return summary_; }
  /// The final report (key=value lines), from the engine's and the bridge's counters.
  std::string Report() const;
  /// Accepted device states never answered (final: call after the engine stopped).
  int64_t Unanswered(const LoopCounters& c) const;
  /// Which device is served, in a sentence for the start-up log (and what to do when none is).
  std::string Serving() const;

 private:
  class Impl;
  BridgeSummary summary_;  // (before impl_: the Impl holds a pointer to it)
  std::unique_ptr<Impl> impl_;
};

}  // namespace tangent::server
