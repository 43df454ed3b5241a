// The bridge's message conversions without sockets: a device state encoded and decoded as on
// the wire becomes the reading and the sample the filter and the servo take; a wrench, the
// tracked contacts and the scene poses come out field for field.

#include "server/lcm_convert.h"

#include <gtest/gtest.h>

#include <vector>

namespace tangent::server {
namespace {

tangent::device_state_t WireRoundTrip(const tangent::device_state_t& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  tangent::device_state_t back;
  EXPECT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return back;
}

TEST(LcmConvertTest, DeviceStateBecomesReadingAndSample) {
  tangent::device_state_t m;
  m.utime = 123456;
  m.device_id = 7;
  m.session = -42;
  m.seq = 99;
  const double position[3] = {0.01, -0.02, 0.03}, orientation[4] = {0.5, 0.5, -0.5, 0.5},
               velocity[3] = {0.1, 0.2, -0.3};
  for (int i = 0; i < 3; ++i) m.position[i] = position[i], m.velocity[i] = velocity[i];
  for (int i = 0; i < 4; ++i) m.orientation[i] = orientation[i];
  m.buttons = 3;
  const tangent::device_state_t w = WireRoundTrip(m);
  const DeviceReading r = ToReading(w);
  EXPECT_EQ(r.device_id, 7);
  EXPECT_EQ(r.session, -42);
  EXPECT_EQ(r.utime, 123456);
  EXPECT_EQ(r.seq, 99);
  const DeviceSample s = ToSample(w, 5, 1000, 777);
  EXPECT_EQ(s.session_index, 5);
  EXPECT_EQ(s.accepted, 1000);
  EXPECT_EQ(s.received_ns, 777);
  EXPECT_EQ(s.buttons, 3);
  EXPECT_EQ(s.seq, 99);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(r.position[i], position[i]);
    EXPECT_EQ(s.position[i], position[i]);
    EXPECT_EQ(r.velocity[i], velocity[i]);
    EXPECT_EQ(s.velocity[i], velocity[i]);
  }
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r.orientation[i], orientation[i]);
    EXPECT_EQ(s.orientation[i], orientation[i]);
  }
}

TEST(LcmConvertTest, EveryDevicePacketHasOneFateAndOnlyAcceptedOnesReachTheServo) {
  DeviceFilterOptions o;
  o.device_id = 1;
  o.takeover_states = 1;  // served from its first state (earning the device: DeviceFilterTest)
  DeviceFilter filter(o);
  tangent::device_state_t scratch;
  DeviceSample sample;
  bool wrong_type = true;
  tangent::device_state_t m{};
  m.device_id = 1;
  m.session = 9;
  m.seq = 1;
  m.orientation[0] = 1.0;
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  const auto size = static_cast<uint32_t>(buf.size());

  EXPECT_EQ(ReadDevicePacket(buf.data(), size, 1000, &filter, &scratch, &sample, &wrong_type),
            PacketFate::kAccepted);
  EXPECT_FALSE(wrong_type);
  EXPECT_EQ(sample.seq, 1);
  EXPECT_EQ(sample.received_ns, 1000);
  EXPECT_EQ(sample.session_index, 1);
  EXPECT_EQ(sample.accepted, 1);
  // The same state again: decoded, refused by the filter (sequence), sample untouched.
  sample.seq = -1;
  EXPECT_EQ(ReadDevicePacket(buf.data(), size, 2000, &filter, &scratch, &sample, &wrong_type),
            PacketFate::kRejected);
  EXPECT_EQ(sample.seq, -1);
  EXPECT_EQ(filter.counts().sequence, 1);
  // Cut short, empty, and another Tangent type's fingerprint: undecodable, the last one named.
  EXPECT_EQ(ReadDevicePacket(buf.data(), size - 1, 3000, &filter, &scratch, &sample, &wrong_type),
            PacketFate::kUndecodable);
  EXPECT_FALSE(wrong_type);
  EXPECT_EQ(ReadDevicePacket(buf.data(), 0, 3000, &filter, &scratch, &sample, &wrong_type),
            PacketFate::kUndecodable);
  tangent::wrench_t w{};
  std::vector<uint8_t> wbuf(static_cast<size_t>(w.getEncodedSize()));
  w.encode(wbuf.data(), 0, static_cast<int>(wbuf.size()));
  EXPECT_EQ(ReadDevicePacket(wbuf.data(), static_cast<uint32_t>(wbuf.size()), 4000, &filter,
                             &scratch, &sample, &wrong_type),
            PacketFate::kUndecodable);
  EXPECT_TRUE(wrong_type);
  EXPECT_EQ(filter.counts().accepted, 1);
}

TEST(LcmConvertTest, WrenchContactsAndSceneComeOutFieldForField) {
  WrenchSample ws;
  ws.utime = 11;
  ws.seq = 12;
  ws.device_id = 13;
  ws.session = 14;
  ws.server_utime = 15;
  ws.force[0] = 1.5;
  ws.force[2] = -0.25;
  ws.torque[1] = 0.125;
  ws.state = kFault;
  tangent::wrench_t w;
  ToWrenchMsg(ws, &w);
  EXPECT_EQ(w.utime, 11);
  EXPECT_EQ(w.seq, 12);
  EXPECT_EQ(w.device_id, 13);
  EXPECT_EQ(w.session, 14);
  EXPECT_EQ(w.server_utime, 15);
  EXPECT_EQ(w.frame, "device");
  EXPECT_EQ(w.force[0], 1.5);
  EXPECT_EQ(w.force[2], -0.25);
  EXPECT_EQ(w.torque[1], 0.125);
  EXPECT_EQ(w.state, kFault);

  Snapshot snap;
  snap.num_contacts = 2;
  snap.contacts[1].surface_a = 3;
  snap.contacts[1].body_b = 2;
  snap.contacts[1].u[3] = 0.75;
  snap.contacts[1].beta = -1e-4;
  snap.contacts[1].p_b[2] = 0.5;
  snap.contacts[1].force = 2.0;
  tangent::contact_states_t cs;
  cs.contacts.resize(5);  // stale storage from an earlier, larger snapshot
  ToContactStates(snap, 99, &cs);
  EXPECT_EQ(cs.utime, 99);
  ASSERT_EQ(cs.num_contacts, 2);
  ASSERT_EQ(cs.contacts.size(), 2u);
  EXPECT_EQ(cs.contacts[1].surface_a, 3);
  EXPECT_EQ(cs.contacts[1].body_b, 2);
  EXPECT_EQ(cs.contacts[1].params[3], 0.75);
  EXPECT_EQ(cs.contacts[1].distance, -1e-4);
  EXPECT_EQ(cs.contacts[1].point_b[2], 0.5);
  EXPECT_EQ(cs.contacts[1].force, 2.0);

  Scene scene;
  scene.mechanism.AddBody(optimizer::Body{"ground"});
  scene.mechanism.AddBody(optimizer::Body{"clip"});
  snap.num_bodies = 2;
  snap.q[1][0] = 0.25;
  snap.q[1][3] = 1.0;
  snap.q[1][6] = -0.5;
  snap.grasp_target[1] = 0.125;
  tangent::scene_state_t ss;
  ToSceneState(snap, scene, 100, &ss);
  EXPECT_EQ(ss.utime, 100);
  ASSERT_EQ(ss.num_bodies, 2);
  EXPECT_EQ(ss.names[1], "clip");
  EXPECT_EQ(ss.position[1][0], 0.25);
  EXPECT_EQ(ss.orientation[1][0], 1.0);
  EXPECT_EQ(ss.orientation[1][3], -0.5);
  EXPECT_EQ(ss.grasp_target[1], 0.125);
}

}  // namespace
}  // namespace tangent::server
