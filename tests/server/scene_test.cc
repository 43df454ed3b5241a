// Scene files: every example scene loads (and certifies its offset meshes); bad scenes are
// rejected with a message naming the file, the item and what is wrong.

#include "server/scene.h"

#include <gtest/gtest.h>

#include <string>

namespace tangent::server {
namespace {

TEST(SceneTest, ExampleScenesLoad) {
  for (const char* name :
       {"paperclips", "fourbar_point", "fourbar_floating", "finger_surface", "peg_in_hole"}) {
    SCOPED_TRACE(name);
    const auto s = LoadScene(std::string(TANGENT_SCENES_DIR) + "/" + name + ".json");
    EXPECT_GE(s->mechanism.num_moving(), 1);
    EXPECT_GE(s->grasp.body, 0);
    EXPECT_EQ(s->device.id,
              std::optional<int64_t>(1));  // each names its device (tangentd serves it)
    for (const SceneSurface& sf : s->surfaces) {
      EXPECT_EQ(sf.watched, !sf.mesh.vertices.empty()) << sf.name;  // meshes only where needed
    }
  }
  const auto clips = LoadScene(std::string(TANGENT_SCENES_DIR) + "/paperclips.json");
  EXPECT_EQ(clips->mechanism.num_bodies(), 3);
  EXPECT_EQ(clips->pairs.size(), 3u);
  EXPECT_NEAR(clips->mechanism.body(1).pose[1], 31.35e-3, 1e-15);  // mm converted
  ASSERT_EQ(clips->load_log.size(), 3u);
  EXPECT_NE(clips->load_log[0].find("0 self-intersecting"), std::string::npos);
}

std::string Error(const std::string& text) {
  try {
    ParseScene(text, "bad.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string LoadSceneError(const std::string& path) {
  try {
    LoadScene(path);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

const char* kBody = R"({"name": "b", "mass": 1})";

std::string Scene(const std::string& bodies, const std::string& rest) {
  return R"({"bodies": [)" + bodies + R"(], "surfaces": [], )" + rest + "}";
}

TEST(SceneTest, BadScenesNameTheProblem) {
  const std::string grasp = R"("grasp": {"body": "b"})";
  EXPECT_NE(Error("{ not json").find("bad.json: not valid JSON"), std::string::npos);
  // A number beyond double range is nlohmann's out_of_range, not a parse_error (scene fuzzer).
  EXPECT_NE(Error("8E888").find("bad.json: not valid JSON"), std::string::npos);
  EXPECT_NE(Error("{\"name\": 1e999}").find("number overflow"), std::string::npos);
  EXPECT_NE(Error("[1, 2]").find("must be a JSON object"), std::string::npos);
  EXPECT_NE(Error(R"({"surfaces": []})").find("missing \"bodies\""), std::string::npos);
  EXPECT_NE(Error(Scene(R"({"name": "b", "mass": -2})", grasp))
                .find("bodies[0].mass: must be positive, got -2"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "least_astonishment": 0)"))
                .find("least_astonishment: must be positive, got 0"),
            std::string::npos);
  EXPECT_NE(Error(Scene(std::string(kBody) + "," + kBody, grasp))
                .find("bodies[1].name: duplicate body name \"b\""),
            std::string::npos);
  EXPECT_NE(Error(Scene(R"({"name": "b", "quaternion": [1, 1, 0, 0]})", grasp))
                .find("bodies[0].quaternion: must be a unit quaternion"),
            std::string::npos);
  EXPECT_NE(Error(Scene(R"({"name": "b", "position": [0, 0]})", grasp))
                .find("bodies[0].position: must be an array of 3 numbers"),
            std::string::npos);
  EXPECT_NE(Error(Scene(R"({"name": "b", "fixed": true})", grasp)).find("no moving body"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, R"("grasp": {"body": "nobody"})"))
                .find("grasp.body: no body named \"nobody\""),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, R"("length_unit": "inch", )" + grasp))
                .find("length_unit: must be \"m\", \"cm\" or \"mm\""),
            std::string::npos);
  EXPECT_NE(
      Error(R"({"bodies": [{"name": "b"}], "surfaces": [{"name": "s", "body": "b", "type": "blob"}],
               "grasp": {"body": "b"}})")
          .find("surfaces[0].type: unknown surface type \"blob\""),
      std::string::npos);
  EXPECT_NE(
      Error(R"({"bodies": [{"name": "b"}], "surfaces": [{"name": "s", "body": "b", "type": "sphere",
               "radius": 0}], "grasp": {"body": "b"}})")
          .find("surfaces[0].radius: must be positive"),
      std::string::npos);
  EXPECT_NE(
      Error(Scene(std::string(kBody) + R"(, {"name": "c"})",
                  R"("joints": [{"type": "hinge", "a": {"body": "b"}, "b": {"body": "c"}}], )" +
                      grasp))
          .find("joints[0].type: unknown joint type \"hinge\""),
      std::string::npos);
  EXPECT_NE(Error(R"({"bodies": [{"name": "b"}, {"name": "c"}],
      "surfaces": [{"name": "s", "body": "b", "type": "sphere", "radius": 1},
                   {"name": "t", "body": "b", "type": "sphere", "radius": 1, "position": [3, 0, 0]}],
      "contacts": [{"a": "s", "b": "t"}], "grasp": {"body": "b"}})")
                .find("contacts[0]: both surfaces are on body \"b\""),
            std::string::npos);
  // Passivity: k must stay below 2b/T and the device's rated stiffness.
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"stiffness": 450, "damping": 0.2})"))
                .find("device.stiffness: exceeds the passivity limit 2 damping / period = 400 N/m"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"stiffness": 800, "damping": 1})"))
                .find("device.stiffness: exceeds the device's rated stiffness 500 N/m"),
            std::string::npos);
  // The device's workspace box (device frame, m) and follow speed.
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"workspace": {"min": [0.01, -0.1, -0.1],
                                                           "max": [0.1, 0.1, 0.1]}})"))
                .find("device.workspace: must contain the device origin strictly (min < 0 < max on "
                      "each axis), got min 0.01, max 0.1 on axis 0"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"workspace": {"min": [-100, -1, -1],
                                                                     "max": [100, 1, 1]}})"))
                .find("device.workspace: is more than 10 m wide on axis 0"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"workspace": {"min": [-1, -1, -1]}})"))
                .find("device.workspace: missing \"max\""),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"follow_speed": 0})"))
                .find("device.follow_speed: must be positive, got 0"),
            std::string::npos);
  // The device served (device_state_t.device_id): a whole 64-bit number.
  for (const char* id : {"1.5", "\"1\"", "18446744073709551615"}) {
    EXPECT_NE(Error(Scene(kBody, grasp + R"(, "device": {"id": )" + std::string(id) + "}"))
                  .find("device.id: must be a 64-bit integer: the device_state_t.device_id the "
                        "server serves"),
              std::string::npos)
        << id;
  }
  EXPECT_NE(LoadSceneError("/nonexistent/scene.json").find("cannot open the scene file"),
            std::string::npos);
}

}  // namespace
}  // namespace tangent::server

namespace tangent::server {
namespace {

// A plate (a plane patch, domain [0, 1]²) on a fixed body with the given "trim".
std::string TrimmedPlate(const std::string& trim) {
  return R"({"bodies": [{"name": "ground", "fixed": true}, {"name": "b", "mass": 1}],
    "surfaces": [{"name": "plate", "body": "ground", "type": "plane_patch", "origin": [0, 0, 0],
                  "edge_u": [0.2, 0, 0], "edge_v": [0, 0.2, 0],
                  "trim": )" +
         trim + R"(}], "grasp": {"body": "b"}})";
}

TEST(SceneTest, BadBodyPairsNameTheProblem) {
  // Two bodies of one sphere each, then the "contacts" entry under test.
  auto scene = [](const std::string& contact, const std::string& third = "") {
    return R"({"bodies": [{"name": "a", "fixed": true}, {"name": "b"})" + third + R"(],
      "surfaces": [{"name": "s", "body": "a", "type": "sphere", "radius": 0.002},
                   {"name": "t", "body": "b", "type": "sphere", "radius": 0.002, "position": [0.01, 0, 0]}],
      "contacts": [)" +
           contact + R"(], "grasp": {"body": "b"}})";
  };
  auto has = [](const std::string& error, const std::string& what) {
    EXPECT_NE(error.find(what), std::string::npos) << error;
  };
  has(Error(scene(R"({"bodies": ["a"]})")), "bad.json: contacts[0].bodies: must name two bodies");
  has(Error(scene(R"({"bodies": ["a", "zz"]})")), "contacts[0].bodies[1]: no body named \"zz\"");
  has(Error(scene(R"({"bodies": ["b", "b"]})")), "contacts[0].bodies: names one body twice");
  has(Error(scene(R"({"bodies": ["a", "c"]})", R"(, {"name": "c"})")),
      "contacts[0].bodies[1]: body \"c\" has no surfaces");
  has(Error(scene(R"({"bodies": ["a", "b"]}, {"bodies": ["b", "a"]})")),
      "contacts[1]: body pair declared twice");
  has(Error(scene(R"({"bodies": ["a", "b"], "kind": "floating"})")),
      "contacts[0].kind: a body pair is \"unilateral\" (non-penetration), got \"floating\"");
  has(Error(scene(R"({"bodies": ["a", "b"], "max_contacts": 9})")),
      "contacts[0].max_contacts: must be an integer from 1 to 8");
  has(Error(scene(R"({"bodies": ["a", "b"], "a": "s"})")), "contacts[0].a: unknown field \"a\"");
  has(Error(scene(R"({"bodies": ["a", "b"]}, {"a": "t", "b": "s"})")),
      "contacts[1]: its bodies \"b\" and \"a\" are declared as a pair");
  has(Error(
          R"({"bodies": [{"name": "a", "fixed": true}, {"name": "b", "fixed": true}, {"name": "c"}],
      "surfaces": [{"name": "s", "body": "a", "type": "sphere", "radius": 0.002},
                   {"name": "t", "body": "b", "type": "sphere", "radius": 0.002, "position": [0.01, 0, 0]}],
      "contacts": [{"bodies": ["a", "b"]}], "grasp": {"body": "c"}})"),
      "contacts[0]: both bodies are fixed");
  // Accepted: four slots by default, every face of both bodies watched.
  const auto ok = ParseScene(scene(R"({"bodies": ["b", "a"]})"), "ok.json");
  ASSERT_EQ(ok->body_pairs.size(), 1u);
  EXPECT_EQ(ok->body_pairs[0].body_a, 1);
  EXPECT_EQ(ok->body_pairs[0].body_b, 0);
  EXPECT_EQ(ok->body_pairs[0].max_contacts, 4);
  for (const SceneSurface& sf : ok->surfaces) {
    EXPECT_TRUE(sf.watched && !sf.mesh.vertices.empty()) << sf.name;
  }
}

TEST(SceneTest, TrimsLoadAndBadLoopsNameTheLoop) {
  const auto s = ParseScene(TrimmedPlate(R"({"holes": [[{"type": "circle", "center": [0.5, 0.5],
                                                       "radius": 0.2, "clockwise": true}]]})"),
                            "plate.json");
  ASSERT_TRUE(s->surfaces[0].trim.has_value());
  EXPECT_FALSE(s->surfaces[0].trim->Contains({0.5, 0.5}));
  EXPECT_TRUE(s->surfaces[0].trim->Contains({0.1, 0.1}));
  // An open loop, crossing loops, a loop outside the domain, a hole outside the outer loop.
  EXPECT_NE(Error(TrimmedPlate(R"({"holes": [[{"type": "polyline",
                                                "points": [[0.2, 0.2], [0.4, 0.2], [0.4, 0.4]]}]]})"))
                .find("surfaces[0].trim: /holes/0: hole 0 is not closed: curve 0 ends at (0.4, "
                      "0.4) but curve 0 starts at (0.2, 0.2)"),
            std::string::npos);
  EXPECT_NE(
      Error(TrimmedPlate(R"({"holes": [[{"type": "circle", "center": [0.4, 0.5], "radius": 0.15}],
                                             [{"type": "circle", "center": [0.6, 0.5], "radius": 0.15}]]})"))
          .find("/holes/1: hole 1 crosses or touches the hole 0"),
      std::string::npos);
  EXPECT_NE(Error(TrimmedPlate(
                      R"({"holes": [[{"type": "circle", "center": [0.95, 0.5], "radius": 0.1}]]})"))
                .find("/holes/0: hole 0: curve 0 leaves the surface's domain (0, 0) to (1, 1)"),
            std::string::npos);
  EXPECT_NE(
      Error(TrimmedPlate(R"({"outer": [{"type": "circle", "center": [0.3, 0.3], "radius": 0.2}],
                                   "holes": [[{"type": "circle", "center": [0.8, 0.8], "radius": 0.1}]]})"))
          .find("/holes/0: hole 0 is not inside the outer loop"),
      std::string::npos);
  // Malformed curves and fields.
  EXPECT_NE(Error(TrimmedPlate(R"({"holes": [[{"type": "spline"}]]})"))
                .find("/holes/0/0/type: expected \"nurbs_curve\", \"polyline\" or \"circle\""),
            std::string::npos);
  EXPECT_NE(Error(TrimmedPlate(
                      R"({"holes": [[{"type": "circle", "center": [0.5, 0.5], "radius": -1}]]})"))
                .find("/holes/0/0/radius: must be positive"),
            std::string::npos);
  EXPECT_NE(Error(TrimmedPlate(R"({"hole": []})")).find("/hole: unknown field"), std::string::npos);
  EXPECT_NE(Error(TrimmedPlate(R"({})")).find("no loop: give \"outer\" or \"holes\""),
            std::string::npos);
}

// The peg-in-hole scene: its global-stage settings, the hole's wall facing its axis, the plate's
// offset mesh cut along the hole; bad global_stage settings name the field.
TEST(SceneTest, GlobalStageSettingsAndTurnedNormals) {
  const auto s = LoadScene(std::string(TANGENT_SCENES_DIR) + "/peg_in_hole.json");
  EXPECT_DOUBLE_EQ(s->global.neglect_radius, 3e-3);
  EXPECT_DOUBLE_EQ(s->global.release, contact::GlobalOptions{}.release);
  const SceneSurface& wall = s->surfaces[static_cast<size_t>(s->SurfaceIndex("hole_wall"))];
  const nurbs::SurfacePoint p = wall.surface.Evaluate(0.3, 0.5, 1);
  const Eigen::Vector3d n = p.S_u.cross(p.S_v).normalized();
  const Eigen::Vector3d radial(p.S.x(), p.S.y(), 0.0);
  EXPECT_NEAR(n.dot(radial.normalized()), -1.0, 1e-12);  // towards the axis
  EXPECT_NEAR(radial.norm(), 5e-3, 1e-15);
  const SceneSurface& top = s->surfaces[static_cast<size_t>(s->SurfaceIndex("plate_top"))];
  EXPECT_FALSE(top.mesh.base.cells.empty());  // cut along the hole
  EXPECT_LT(top.mesh.base.triangles.size(),
            (top.mesh.base.u_lines.size() - 1) * (top.mesh.base.v_lines.size() - 1) * 2);
  const std::string grasp = R"("grasp": {"body": "b"})";
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "global_stage": {"neglect_radius": -1})"))
                .find("bad.json: global_stage.neglect_radius: must be positive"),
            std::string::npos);
  EXPECT_NE(
      Error(Scene(kBody, grasp + R"(, "global_stage": {"activation": 0.2e-3, "release": 0.1e-3})"))
          .find("global_stage.release: must exceed \"activation\""),
      std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "global_stage": {"release": 0.3e-3})"))
                .find("is below the global stage's release"),
            std::string::npos);
  EXPECT_NE(Error(Scene(kBody, grasp + R"(, "offset": {"margin": 0.1e-3})"))
                .find("offset: margin 0.0001"),
            std::string::npos);
}

}  // namespace
}  // namespace tangent::server
