#include "view/timeline.h"

#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

namespace tangent::view {
namespace {

std::unique_ptr<server::Scene> OneClip() {
  server::SceneLoadOptions o;
  o.offset_meshes = false;
  return server::ParseScene(
      R"({"name":"one clip","length_unit":"mm",
          "bodies":[{"name":"a","position":[0,0,0]}],
          "surfaces":[{"name":"wa","body":"a","type":"paperclip"}],
          "grasp":{"body":"a","point":[0,20,0]}})",
      "one_clip.json", ".", o);
}

template <class Msg>
void Write(lcm::LogFile* log, const std::string& channel, const Msg& m, int64_t t) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent e{0, t, channel, static_cast<int32_t>(buf.size()), buf.data()};
  ASSERT_EQ(log->writeEvent(&e), 0);
}

scene_state_t At(int64_t utime, double x) {
  scene_state_t m;
  m.utime = utime;
  m.num_bodies = 1;
  m.names = {"a"};
  m.position = {{x, 0, 0}};
  m.orientation = {{1, 0, 0, 0}};
  m.grasp_target[0] = m.grasp_target[1] = m.grasp_target[2] = 0;
  return m;
}

TEST(TimelineTest, ReplaysTheLoggedStatesByTimeAndSkipsWhatDoesNotFit) {
  const auto scene = OneClip();
  const std::string path = ::testing::TempDir() + "/timeline_test.lcmlog";
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    Write(&log, "TANGENT_SCENE", At(1'000'000, 0.0), 1);
    Write(&log, "TANGENT_SCENE", At(1'500'000, 0.5), 2);
    contact_states_t c;
    c.utime = 1'600'000;
    c.num_contacts = 1;
    contact_state_t s{};
    s.surface_a = 5;  // out of range: skipped
    c.contacts.push_back(s);
    Write(&log, "TANGENT_CONTACTS", c, 3);
    const uint8_t junk[3] = {1, 2, 3};
    lcm::LogEvent e{0, 4, "TANGENT_SCENE", 3, const_cast<uint8_t*>(junk)};
    ASSERT_EQ(log.writeEvent(&e), 0);
    Write(&log, "TANGENT_SCENE", At(2'000'000, 1.0), 5);
    Write(&log, "OTHER", At(9'000'000, 9.0), 6);  // another channel: ignored
  }
  const Timeline t(path, *scene, server::Channels{});
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t.skipped(), 2);
  EXPECT_DOUBLE_EQ(t.duration(), 1.0);
  EXPECT_EQ(t.At(-1.0).poses[0][0], 0.0);
  EXPECT_EQ(t.At(0.49).poses[0][0], 0.0);
  EXPECT_EQ(t.At(0.5).poses[0][0], 0.5);
  EXPECT_EQ(t.At(0.99).poses[0][0], 0.5);
  EXPECT_EQ(t.At(5.0).poses[0][0], 1.0);
  std::filesystem::remove(path);
}

TEST(TimelineTest, AMissingOrEmptyLogIsAnErrorNamingIt) {
  const auto scene = OneClip();
  try {
    Timeline("/nonexistent/run.lcmlog", *scene, server::Channels{});
    FAIL();
  } catch (const TimelineError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/run.lcmlog: cannot open the LCM log for reading");
  }
  const std::string path = ::testing::TempDir() + "/empty.lcmlog";
  { lcm::LogFile log(path, "w"); }
  try {
    Timeline(path, *scene, server::Channels{});
    FAIL();
  } catch (const TimelineError& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": no scene_state_t of scene \"one clip\" on channel "
                                         "TANGENT_SCENE (0 messages skipped)");
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace tangent::view
