// Run files: a good one parses into the scene's names; every kind of bad input is rejected with
// a message naming the file, the JSON pointer of the item and the problem.

#include "design/run_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace tangent::design {
namespace {

using ::testing::HasSubstr;

const std::string kGood = R"({
  "scene": "three_link_finger.json",
  "objective": {"sense": "maximize", "terms": [{"measure": "dexterity",
      "end_effector": {"body": "distal", "point": [0, 0, 0.2]},
      "joints": ["turntable", "knuckle", "middle joint"]}]},
  "constraints": [{"name": "tip on the surface", "type": "point_on_surface",
                   "at": {"body": "distal", "point": [0, 0, 0.2]}, "surface": "terrain"}],
  "bounds": [{"joint": "knuckle", "min_deg": 10, "max_deg": 150}],
  "starts": {"list": [{"joints_deg": {"knuckle": 60}}], "random": 3, "seed": 5}
})";

RunSpec Parse(const std::string& text) { return ParseRun(text, "run.json", TANGENT_SCENES_DIR); }

// The error of a run file made from kGood by replacing `from` with `to`.
std::string ErrorOf(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  try {
    Parse(text);
  } catch (const RunError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << to;
  return "";
}

TEST(RunFileTest, AGoodRunFileNamesTheScenesParts) {
  const RunSpec run = Parse(kGood);
  EXPECT_TRUE(run.maximize);
  ASSERT_EQ(run.terms.size(), 1u);
  EXPECT_EQ(run.terms[0].joints.size(), 3u);
  ASSERT_EQ(run.constraints.size(), 1u);
  EXPECT_GE(run.constraints[0].surface, 0);
  EXPECT_FALSE(run.constraints[0].inequality);
  ASSERT_EQ(run.bounds.size(), 1u);
  EXPECT_NEAR(run.bounds[0].hi, 150.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(run.num_cases(), 4);
  EXPECT_EQ(run.seed, 5u);
  EXPECT_EQ(run.random_joints.size(), 3u);  // every revolute joint by default
}

TEST(RunFileTest, BadInputIsRejectedNamingFilePointerAndProblem) {
  EXPECT_EQ(ErrorOf("\"objective\"", "\"objectve\""),
            "run.json: /objectve: unknown field \"objectve\" (known: bounds, comment, "
            "configurations, constraints, design, grid, length_unit, objective, scene, solver, "
            "starts)");
  EXPECT_THAT(ErrorOf("three_link_finger.json", "nowhere.json"),
              HasSubstr("run.json: /scene: the scene could not be loaded: "));
  EXPECT_THAT(ErrorOf("\"middle joint\"]", "\"midle joint\"]"),
              HasSubstr("run.json: /objective/terms/0/joints/2: no joint named \"midle joint\" in "
                        "the scene (joints: turntable, knuckle, middle joint)"));
  EXPECT_EQ(ErrorOf("\"max_deg\": 150", "\"max_deg\": 5"),
            "run.json: /bounds/0: empty or inverted bounds: min_deg must be below max_deg");
  EXPECT_EQ(ErrorOf("\"max_deg\": 150", "\"max_deg\": 10"),
            "run.json: /bounds/0: empty or inverted bounds: min_deg must be below max_deg");
  // JSON has no NaN or infinity; a number beyond a double is the non-finite input a file can hold.
  EXPECT_THAT(ErrorOf("\"max_deg\": 150", "\"max_deg\": 1e999"),
              HasSubstr("run.json: not valid JSON: [json.exception.out_of_range.406] number "
                        "overflow parsing '1e999'"));
  EXPECT_EQ(ErrorOf("\"measure\": \"dexterity\"", "\"measure\": \"dexterty\""),
            "run.json: /objective/terms/0/measure: unknown measure \"dexterty\" (dexterity, "
            "inverse_condition, force_transmission, grasp_distance)");
  EXPECT_EQ(ErrorOf("\"surface\": \"terrain\"", "\"surface\": \"terain\""),
            "run.json: /constraints/0/surface: no surface named \"terain\"");
  EXPECT_EQ(ErrorOf("\"type\": \"point_on_surface\"", "\"type\": \"glue\""),
            "run.json: /constraints/0/type: unknown constraint type \"glue\" (plane, half_space, "
            "point, line, point_on_surface, point_above_surface)");
  EXPECT_EQ(ErrorOf("\"sense\": \"maximize\"", "\"sense\": \"best\""),
            "run.json: /objective/sense: must be \"maximize\" or \"minimize\", got \"best\"");
  EXPECT_EQ(ErrorOf("\"joint\": \"knuckle\"", "\"joint\": \"turntable\", \"extra\": 1"),
            "run.json: /bounds/0/extra: unknown field \"extra\" (known: joint, max_deg, min_deg)");
  EXPECT_EQ(ErrorOf("\"random\": 3", "\"random\": -1"),
            "run.json: /starts/random: must be in [0, 1000000], got -1");
  EXPECT_EQ(
      ErrorOf("\"list\": [{\"joints_deg\": {\"knuckle\": 60}}], \"random\": 3", "\"random\": 0"),
      "run.json: /starts: no start: give \"list\" or \"random\" > 0");
  EXPECT_EQ(ErrorOf("\"surface\": \"terrain\"", "\"surface\": \"terrain\", \"rhs\": [1, 2]"),
            "run.json: /constraints/0/rhs: must have 1 numbers, got 2");
  EXPECT_EQ(ErrorOf("\"body\": \"distal\", \"point\": [0, 0, 0.2]}, \"surface\"",
                    "\"body\": \"ground\"}, \"surface\""),
            "run.json: /constraints/0/at: the point is on the surface's own body");
  EXPECT_EQ(ErrorOf("\"scene\": \"three_link_finger.json\"", "\"scene\": 3"),
            "run.json: /scene: must be a string");
  try {
    Parse("{ not json");
    ADD_FAILURE();
  } catch (const RunError& e) {
    EXPECT_THAT(e.what(), HasSubstr("run.json: not valid JSON: "));
  }
}

TEST(RunFileTest, GridAxesAreCheckedAndMultiplyTheCases) {
  auto with_grid = [](const std::string& grid) {
    std::string text = kGood;
    text.replace(text.find("\"starts\""), 8, "\"grid\": " + grid + ", \"starts\"");
    return text;
  };
  const RunSpec run =
      Parse(with_grid(R"([{"constraint": "tip on the surface", "range": [0, 0.01, 3]}])"));
  ASSERT_EQ(run.grid.size(), 1u);
  EXPECT_EQ(run.grid[0].values, (std::vector<double>{0.0, 0.005, 0.01}));
  EXPECT_EQ(run.num_cases(), 4 * 3);
  auto error = [&](const std::string& grid) {
    try {
      Parse(with_grid(grid));
    } catch (const RunError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(R"([{"constraint": "tip", "values": [0]}])"),
            "run.json: /grid/0/constraint: no constraint named \"tip\"");
  EXPECT_EQ(error(R"([{"constraint": "tip on the surface", "range": [1, 0, 3]}])"),
            "run.json: /grid/0/range: empty or inverted range: first must be below last");
  EXPECT_EQ(error(R"([{"constraint": "tip on the surface", "range": [0, 1, 1]}])"),
            "run.json: /grid/0/range/2: the count must be an integer in [2, 10000]");
  EXPECT_EQ(error(R"([{"constraint": "tip on the surface", "values": [0], "range": [0, 1, 2]}])"),
            "run.json: /grid/0: give either \"values\" or \"range\"");
  EXPECT_EQ(error(R"([{"constraint": "tip on the surface", "row": 1, "values": [0]}])"),
            "run.json: /grid/0/row: must be in [0, 0], got 1");
}

TEST(RunFileTest, DesignJointsAreCheckedByType) {
  auto error = [](const std::string& design) {
    const std::string text = R"({"scene": "three_link_finger_design.json",
      "objective": {"terms": [{"measure": "dexterity", "end_effector": {"body": "distal"},
                               "joints": ["turntable", "knuckle", "middle joint"]}]},
      "design": )" + design + R"(, "starts": {"random": 1}})";
    try {
      const RunSpec run = Parse(text);
      return "accepted " + std::to_string(run.design_joints.size());
    } catch (const RunError& e) {
      return std::string(e.what());
    }
  };
  EXPECT_EQ(error(R"([{"joint": "middle length", "min": -0.1, "max": 0.1}])"), "accepted 1");
  EXPECT_EQ(error(R"([{"joint": "middle length", "min": 0.1, "max": -0.1}])"),
            "run.json: /design/0: empty or inverted bounds: the minimum must be below the "
            "maximum");
  EXPECT_EQ(error(R"([{"joint": "knuckle", "min_deg": 0, "max_deg": 90}])"),
            "run.json: /design/0/joint: a design joint cannot drive a measure's motion");
  EXPECT_EQ(error(R"([{"joint": "middle length", "min_deg": 0, "max_deg": 90}])"),
            "run.json: /design/0/max_deg: unknown field \"max_deg\" (known: joint, max, min)");
}

TEST(RunFileTest, AGraspDistanceMustEnterAsACost) {
  const std::string text = R"({
    "scene": "three_link_finger.json",
    "objective": {"sense": "maximize", "terms": [{"measure": "grasp_distance", "weight": 1,
        "end_effector": {"body": "distal"}, "target": [0.1, 0, 0.1]}]},
    "starts": {"random": 1}})";
  try {
    Parse(text);
    ADD_FAILURE();
  } catch (const RunError& e) {
    EXPECT_STREQ(e.what(),
                 "run.json: /objective/terms/0/weight: grasp_distance would reward moving away "
                 "from the target; give it a negative weight");
  }
}

TEST(RunFileTest, AMissingFileIsNamed) {
  try {
    LoadRun("/nonexistent/run.json");
    ADD_FAILURE();
  } catch (const RunError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/run.json: cannot open the run file");
  }
}

}  // namespace
}  // namespace tangent::design
