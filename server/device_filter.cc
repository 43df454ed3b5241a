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
      lost_budget_ = o_.seq_slack;
      budget_ns_ = received_ns;
      last_takeover_ns_ = received_ns;
      any_takeover_ = true;
      if (!device_) device_ = m.device_id;               // (the "any" choice: the first to earn it)
      for (Candidate& c : candidates_) c = Candidate{};  // every other session earns afresh
      ++counts_.sessions;
      [[fallthrough]];
    case Verdict::kAccepted:
      ++counts_.accepted;
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
    case Verdict::kPending:
      ++counts_.pending;
      break;
  }
  return v;
}

DeviceFilter::Verdict DeviceFilter::Judge(const DeviceReading& m, int64_t received_ns) {
  if (!Served(m.device_id)) return Verdict::kDeviceId;
  const bool served = have_session_ && m.session == session_;
  const bool owner_live = have_session_ && received_ns - last_ns_ < Ns(o_.owner_timeout);
  if (!served && owner_live && Retired(m.session)) return Verdict::kStaleSession;
  // Every state of the served session is counted here, whatever its content.
  if (served) CountSequence(m, received_ns);
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
  if (!served) return Earn(m, received_ns, owner_live);
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

void DeviceFilter::CountSequence(const DeviceReading& m, int64_t received_ns) {
  if (m.seq <= highest_seq_) return;
  // A client sends at most max_state_rate states a second: a gap larger than the session could
  // have lost (the bucket) was never sent. It is a reset of the numbering (a client's bug, or an
  // attack on the counter), counted as such; only a plausible gap is states that never reached
  // the server.
  const double refill = o_.max_state_rate * 1e-9 * static_cast<double>(received_ns - budget_ns_);
  lost_budget_ = std::min(lost_budget_ + refill, o_.seq_slack + o_.max_state_rate);
  budget_ns_ = received_ns;
  const int64_t gap = m.seq - highest_seq_ - 1;
  if (static_cast<double>(gap) > lost_budget_) {
    ++counts_.seq_resets;
  } else {
    counts_.lost += gap;
    lost_budget_ -= static_cast<double>(gap);
  }
  highest_seq_ = m.seq;
}

DeviceFilter::Verdict DeviceFilter::Earn(const DeviceReading& m, int64_t received_ns,
                                         bool owner_live) {
  Candidate* c = nullptr;
  for (Candidate& k : candidates_) {
    if (k.streak > 0 && k.session == m.session && k.device_id == m.device_id) c = &k;
  }
  // Where the hand is: no further from the current grasp point than a hand moves a stylus
  // since the owner's last accepted state (after reacquire_after of silence, anywhere).
  if (have_session_) {
    const double dt = 1e-9 * static_cast<double>(received_ns - last_ns_);
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) d2 += (m.position[i] - last_p_[i]) * (m.position[i] - last_p_[i]);
    if (dt <= o_.reacquire_after && std::sqrt(d2) > o_.min_jump &&
        std::sqrt(d2) > o_.max_speed * std::max(dt, 1e-3)) {
      if (c) *c = Candidate{};
      return Verdict::kJump;
    }
  }
  if (c && m.seq <= c->last_seq) return Verdict::kSequence;  // a repeat breaks no streak
  if (!c) {
    // A free slot, else the one with the shortest streak (the oldest of those): a burst of
    // one-state sessions cannot push out a session that is earning the device.
    c = &candidates_[0];
    for (Candidate& k : candidates_) {
      if (k.streak < c->streak || (k.streak == c->streak && k.last_ns < c->last_ns)) c = &k;
    }
    *c = Candidate{m.device_id, m.session, m.seq, received_ns, 0};
  } else if (received_ns - c->last_ns > Ns(o_.takeover_gap)) {
    c->streak = 0;  // not steady: start again
  }
  c->last_seq = m.seq;
  c->last_ns = received_ns;
  if (++c->streak < o_.takeover_states) return Verdict::kPending;
  if (owner_live && any_takeover_ && received_ns - last_takeover_ns_ < Ns(o_.takeover_interval)) {
    return Verdict::kPending;  // earned; served once the interval has passed
  }
  return Verdict::kNewSession;
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
    case Verdict::kPending:
      return "session earning the device (not yet served)";
  }
  return "?";
}

}  // namespace tangent::server
