#include "server/device_filter.h"

#include <algorithm>
#include <cmath>

namespace tangent::server {

DeviceFilter::DeviceFilter(const DeviceFilterOptions& o) : o_(o), device_(o.device_id) {}

DeviceFilter::Verdict DeviceFilter::Check(const DeviceReading& m, int64_t received_ns) {
  const Verdict v = Judge(m, received_ns);
  switch (v) {
    case Verdict::kNewSession:
      if (have_session_) Retire(session_);
      have_session_ = true;
      session_ = m.session;
      highest_seq_ = m.seq;
      ++counts_.sessions;
      [[fallthrough]];
    case Verdict::kAccepted:
      ++counts_.accepted;
      if (!device_) device_ = m.device_id;
      last_seq_ = m.seq;
      last_ns_ = received_ns;
      for (int i = 0; i < 3; ++i) last_p_[i] = m.position[i];
      break;
    case Verdict::kNonFinite:
      ++counts_.non_finite;
      break;
    case Verdict::kQuaternion:
      ++counts_.quaternion;
      break;
    case Verdict::kWorkspace:
      ++counts_.workspace;
      break;
    case Verdict::kDeviceId:
      ++counts_.device;
      break;
    case Verdict::kStaleSession:
      ++counts_.session;
      break;
    case Verdict::kSequence:
      ++counts_.sequence;
      break;
    case Verdict::kJump:
      ++counts_.jump;
      break;
  }
  return v;
}

DeviceFilter::Verdict DeviceFilter::Judge(const DeviceReading& m, int64_t received_ns) {
  if (device_ && m.device_id != *device_) return Verdict::kDeviceId;
  const bool served = have_session_ && m.session == session_;
  if (!served && Retired(m.session)) return Verdict::kStaleSession;
  if (served && m.seq > highest_seq_) {
    // Every state of the served session passes here, whatever its content: a gap in seq is a
    // state that never reached the server.
    if (m.seq > highest_seq_ + 1) counts_.lost += m.seq - highest_seq_ - 1;
    highest_seq_ = m.seq;
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(m.position[i]) || !std::isfinite(m.velocity[i])) return Verdict::kNonFinite;
  }
  double n2 = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(m.orientation[i])) return Verdict::kNonFinite;
    n2 += m.orientation[i] * m.orientation[i];
  }
  if (std::abs(std::sqrt(n2) - 1.0) > o_.quaternion_tolerance) return Verdict::kQuaternion;
  for (int i = 0; i < 3; ++i) {
    if (!(m.position[i] >= o_.workspace_min[i] && m.position[i] <= o_.workspace_max[i])) {
      return Verdict::kWorkspace;
    }
  }
  if (!served) return Verdict::kNewSession;
  if (m.seq <= last_seq_) return Verdict::kSequence;
  const double dt = 1e-9 * static_cast<double>(received_ns - last_ns_);
  if (dt > o_.reacquire_after) return Verdict::kAccepted;
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) d2 += (m.position[i] - last_p_[i]) * (m.position[i] - last_p_[i]);
  const double d = std::sqrt(d2);
  // A state may arrive right behind the previous one (the network batches): the speed is
  // judged over at least a millisecond, the device's period.
  if (d > o_.min_jump && d > o_.max_speed * std::max(dt, 1e-3)) return Verdict::kJump;
  return Verdict::kAccepted;
}

bool DeviceFilter::Retired(int64_t session) const {
  const int n = std::min(retired_count_, kRetired);
  for (int i = 0; i < n; ++i) {
    if (retired_[i] == session) return true;
  }
  return false;
}

void DeviceFilter::Retire(int64_t session) { retired_[retired_count_++ % kRetired] = session; }

const char* DeviceFilter::ToString(Verdict v) {
  switch (v) {
    case Verdict::kAccepted:
      return "accepted";
    case Verdict::kNewSession:
      return "accepted: new session";
    case Verdict::kNonFinite:
      return "non-finite field";
    case Verdict::kQuaternion:
      return "orientation not a unit quaternion";
    case Verdict::kWorkspace:
      return "position outside the device workspace";
    case Verdict::kDeviceId:
      return "device id not served";
    case Verdict::kStaleSession:
      return "stale session (taken over)";
    case Verdict::kSequence:
      return "stale or repeated sequence number";
    case Verdict::kJump:
      return "implausible jump";
  }
  return "?";
}

}  // namespace tangent::server
