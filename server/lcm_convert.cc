#include "server/lcm_convert.h"

#include <cstring>

#include <tangent/loop_stats_t.hpp>

namespace tangent::server {

DeviceReading ToReading(const tangent::device_state_t& m) {
  DeviceReading r;
  r.device_id = m.device_id;
  r.session = m.session;
  r.utime = m.utime;
  r.seq = m.seq;
  std::memcpy(r.position, m.position, sizeof(r.position));
  std::memcpy(r.orientation, m.orientation, sizeof(r.orientation));
  std::memcpy(r.velocity, m.velocity, sizeof(r.velocity));
  return r;
}

namespace {

/// Whether a packet starts with the fingerprint of another Tangent message type.
bool IsOtherTangentType(const void* data, uint32_t size) {
  if (size < 8) return false;
  int64_t hash = 0;
  const auto* b = static_cast<const uint8_t*>(data);
  for (int i = 0; i < 8; ++i)
    hash = static_cast<int64_t>((static_cast<uint64_t>(hash) << 8) | b[i]);
  const int64_t others[] = {tangent::wrench_t::getHash(), tangent::loop_stats_t::getHash(),
                            tangent::scene_state_t::getHash(),
                            tangent::contact_states_t::getHash()};
  for (int64_t h : others) {
    if (hash == h) return true;
  }
  return false;
}

}  // namespace

PacketFate ReadDevicePacket(const void* data, uint32_t size, int64_t received_ns,
                            DeviceFilter* filter, tangent::device_state_t* scratch,
                            DeviceSample* sample, bool* wrong_type) {
  *wrong_type = false;
  if (size > static_cast<uint32_t>(INT32_MAX) ||
      scratch->decode(data, 0, static_cast<int>(size)) < 0) {
    *wrong_type = IsOtherTangentType(data, size);
    return PacketFate::kUndecodable;
  }
  const DeviceFilter::Verdict v = filter->Check(ToReading(*scratch), received_ns);
  if (!DeviceFilter::Accepted(v)) return PacketFate::kRejected;
  *sample = ToSample(*scratch, filter->session_index(), filter->counts().accepted, received_ns);
  return PacketFate::kAccepted;
}

DeviceSample ToSample(const tangent::device_state_t& m, int64_t session_index, int64_t accepted,
                      int64_t received_ns) {
  DeviceSample s;
  s.utime = m.utime;
  s.device_id = m.device_id;
  s.session = m.session;
  s.seq = m.seq;
  s.session_index = session_index;
  s.accepted = accepted;
  std::memcpy(s.position, m.position, sizeof(s.position));
  std::memcpy(s.orientation, m.orientation, sizeof(s.orientation));
  std::memcpy(s.velocity, m.velocity, sizeof(s.velocity));
  s.buttons = m.buttons;
  s.received_ns = received_ns;
  return s;
}

void ToWrenchMsg(const WrenchSample& w, tangent::wrench_t* out) {
  out->utime = w.utime;
  out->device_id = w.device_id;
  out->session = w.session;
  out->seq = w.seq;
  out->server_utime = w.server_utime;
  out->frame = "device";
  for (int i = 0; i < 3; ++i) {
    out->force[i] = w.force[i];
    out->torque[i] = w.torque[i];
  }
  out->state = w.state;
}

void ToContactStates(const Snapshot& snap, int64_t utime, tangent::contact_states_t* out) {
  out->utime = utime;
  out->num_contacts = snap.num_contacts;
  out->contacts.resize(static_cast<size_t>(snap.num_contacts));
  for (int k = 0; k < snap.num_contacts; ++k) {
    const TrackedContact& c = snap.contacts[k];
    tangent::contact_state_t& m = out->contacts[static_cast<size_t>(k)];
    m.body_a = c.body_a;
    m.body_b = c.body_b;
    m.surface_a = c.surface_a;
    m.surface_b = c.surface_b;
    std::memcpy(m.params, c.u, sizeof(m.params));
    m.distance = c.beta;
    std::memcpy(m.point_a, c.p_a, sizeof(m.point_a));
    std::memcpy(m.point_b, c.p_b, sizeof(m.point_b));
    m.force = c.force;
  }
}

void ToSceneState(const Snapshot& snap, const Scene& scene, int64_t utime,
                  tangent::scene_state_t* out) {
  const size_t n = static_cast<size_t>(snap.num_bodies);
  out->utime = utime;
  out->num_bodies = snap.num_bodies;
  out->names.resize(n);
  out->position.resize(n, std::vector<double>(3));
  out->orientation.resize(n, std::vector<double>(4));
  for (int b = 0; b < snap.num_bodies; ++b) {
    const size_t k = static_cast<size_t>(b);
    out->names[k] = scene.mechanism.body(b).name;
    out->position[k].resize(3);
    out->orientation[k].resize(4);
    for (int i = 0; i < 3; ++i) out->position[k][static_cast<size_t>(i)] = snap.q[b][i];
    for (int i = 0; i < 4; ++i) out->orientation[k][static_cast<size_t>(i)] = snap.q[b][3 + i];
  }
  std::memcpy(out->grasp_target, snap.grasp_target, sizeof(out->grasp_target));
}

}  // namespace tangent::server
