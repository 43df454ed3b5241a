// The Engine's threads on the paperclip scene: a device state published while the servo sleeps
// is answered at once (the doorbell), not at the next scheduled tick; each answer echoes its
// device state and comes once. The global stage's clearance trees are built before it serves.

#include "server/engine.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>

namespace tangent::server {
namespace {

TEST(EngineTest, ADeviceStateWakesTheSleepingServoAndIsAnsweredOnce) {
  auto scene = LoadScene(std::string(TANGENT_SCENES_DIR) + "/paperclips.json");
  EngineOptions o;
  o.rate_hz = 1.0;  // one scheduled tick a second: an answer within the second is the doorbell's
  o.servo_cpu = o.global_cpu = -1;
  Engine engine(*scene, o);
  // Every clip's wire is watched, and its clearance tree is built before the threads run.
  EXPECT_EQ(engine.clearance_trees(), static_cast<int>(scene->surfaces.size()));
  engine.Start();
  // The first scheduled tick is a second after Start: the servo sleeps now.
  WrenchSample w;
  for (int k = 1; k <= 3; ++k) {
    DeviceSample s;
    s.seq = k;
    s.utime = 1000 * k;
    s.received_ns = MonotonicNs();
    engine.Publish(s);
    bool answered = false;
    const int64_t deadline = s.received_ns + 400'000'000;  // well before the scheduled tick
    while (!answered && MonotonicNs() < deadline) {
      if (engine.wrenches().Pop(&w)) {
        answered = true;
        EXPECT_EQ(w.seq, k);
        EXPECT_EQ(w.utime, 1000 * k);
        EXPECT_GE(w.tick_start_ns, s.received_ns);
      }
    }
    EXPECT_TRUE(answered) << "device state " << k << " waited for the scheduled tick";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EXPECT_FALSE(engine.wrenches().Pop(&w)) << "answered twice";
  }
  engine.Stop();
  LoopCounters c;
  engine.counters().Read(&c);
  EXPECT_GE(c.early_ticks, 3);
}

TEST(EngineTest, TheServoTakesTheGlobalStagesClearanceCertificates) {
  // A plate held 1 mm over eight domes: every pair apart, so each pass certifies them, and the
  // servo thread takes the certificates (through the seqlock it never waits on).
  auto scene = LoadScene(std::string(TANGENT_SCENES_DIR) + "/contact_burst.json");
  EngineOptions o;
  o.servo_cpu = o.global_cpu = -1;
  Engine engine(*scene, o);
  EXPECT_EQ(engine.clearance_trees(), static_cast<int>(scene->surfaces.size()));  // 9, up front
  engine.Start();
  LoopCounters c;
  const int64_t deadline = MonotonicNs() + 5'000'000'000;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    engine.counters().Read(&c);
  } while (c.clearances_taken < 20 && MonotonicNs() < deadline);
  engine.Stop();
  engine.counters().Read(&c);
  EXPECT_GE(c.clearances_taken, 20);
  EXPECT_EQ(c.faults, 0);
}

}  // namespace
}  // namespace tangent::server
