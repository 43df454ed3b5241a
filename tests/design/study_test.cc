// Design studies end to end (tangent-opt's library): the finger example against IPOPT from
// every start, sensitivities against re-solved differences, bit-identical results on one or two
// threads, resuming from a journal, and an infeasible constraint set reported as infeasible.

#include "design/study.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "design/runner.h"
#include "testing/ipopt_problem.h"

namespace tangent::design {
namespace {

const std::string kScenes = TANGENT_SCENES_DIR;

RunSpec Parse(const std::string& text) { return ParseRun(text, "run.json", kScenes); }

// The finger with the tip on the surface (rhs: its height above it) and a knuckle bound.
std::string FingerRun(double tip_rhs, double knuckle_max_deg, const std::string& starts) {
  char text[2048];
  std::snprintf(text, sizeof(text), R"({
    "scene": "three_link_finger.json",
    "objective": {"terms": [{"measure": "dexterity",
        "end_effector": {"body": "distal", "point": [0, 0, 0.2]},
        "joints": ["turntable", "knuckle", "middle joint"]}]},
    "constraints": [{"name": "tip on the surface", "type": "point_on_surface", "rhs": %.17g,
                     "at": {"body": "distal", "point": [0, 0, 0.2]}, "surface": "terrain"}],
    "bounds": [{"joint": "knuckle", "min_deg": 10, "max_deg": %.17g}],
    "starts": %s})",
                tip_rhs, knuckle_max_deg, starts.c_str());
  return text;
}

// Every start of an example run: ours against IPOPT from the same assembled start. The listed
// starts must reach IPOPT's optimum; from a random start the two solvers may climb to different
// local maxima, which is counted, not failed.
void CompareWithIpopt(const std::string& run_file) {
  const Study study(LoadRun(kScenes + "/" + run_file));
  optimizer::testing::IpoptSolver ipopt(study.problem());
  const int listed = static_cast<int>(study.run().starts.size());
  int compared = 0, same = 0;
  for (int i = 0; i < study.num_cases(); ++i) {
    const CaseResult ours = study.Solve(i);
    bool ok = false;
    const Eigen::VectorXd q0 = study.StartConfiguration(i, &ok);
    ASSERT_TRUE(ok) << i;
    study.PrepareData(i, q0, &ipopt.data());
    const optimizer::testing::IpoptResult ref = ipopt.Solve(q0);
    std::printf("%s case %d: ours %.10f (%s, %d iterations, %.1f ms), IPOPT %.10f (%s, %d)\n",
                run_file.c_str(), i, ours.objective, ours.status.c_str(), ours.iterations,
                ours.time_ms, study.Objective(ref.q), ref.solved ? "solved" : "failed",
                ref.iterations);
    EXPECT_EQ(ours.status, "optimum") << i;
    EXPECT_LE(ours.violation, study.run().constraint_tolerance) << i;
    if (!ref.solved) continue;  // the comparison is over the starts IPOPT also solves
    ++compared;
    const double theirs = study.Objective(ref.q);
    const bool agree = std::abs(ours.objective - theirs) <= 1e-6 * std::abs(theirs);
    same += agree;
    if (i < listed) {
      EXPECT_TRUE(agree) << i << ": " << ours.objective << " vs " << theirs;
    }
  }
  std::printf("%s: %d of %d starts both solved reach the same optimum\n", run_file.c_str(), same,
              compared);
  EXPECT_GE(compared, listed);
}

TEST(StudyTest, FingerExampleReachesIpoptsOptimumFromEveryListedStart) {
  CompareWithIpopt("three_link_finger.run.json");
}

TEST(StudyTest, FourBarExampleReachesIpoptsOptimumFromEveryListedStart) {
  CompareWithIpopt("fourbar_dexterity.run.json");
}

TEST(StudyTest, AdjustableLinkExampleReachesIpoptsOptimumFromEveryListedStart) {
  CompareWithIpopt("three_link_finger_design.run.json");
}

TEST(StudyTest, ADesignJointsBoundSensitivityMatchesReSolvedDifferences) {
  // The middle link's length at its upper bound: dF*/d(max) against re-solves with the bound
  // moved by ±ε (metres).
  auto run_with_max = [](double max) {
    std::ifstream in(kScenes + "/three_link_finger_design.run.json");
    nlohmann::json j = nlohmann::json::parse(in);
    j["design"][0]["max"] = max;
    j["starts"] = nlohmann::json::parse(R"({"list": [{"joints_deg": {"turntable": -120,
        "knuckle": 100, "middle joint": 40}, "joints_m": {"middle length": 0.0}}]})");
    return Study(ParseRun(j.dump(), "run.json", kScenes)).Solve(0);
  };
  const CaseResult r = run_with_max(0.1);
  ASSERT_EQ(r.status, "optimum");
  ASSERT_EQ(r.design.size(), 1u);
  EXPECT_NEAR(r.design[0].second, 0.1, 1e-12);  // the longest link allowed
  double reported = 0.0;
  for (const Sensitivity& s : r.sensitivities) {
    if (s.constraint == "design middle length" && s.wrt == "max") reported = s.derivative;
  }
  const double eps = 1e-5;
  const double fd =
      (run_with_max(0.1 + eps).objective - run_with_max(0.1 - eps).objective) / (2 * eps);
  std::printf("dF/d(max length): reported %.9g, re-solved %.9g\n", reported, fd);
  EXPECT_GT(reported, 0.0);
  EXPECT_NEAR(reported, fd, 1e-4 * std::abs(fd));
}

TEST(StudyTest, SensitivitiesMatchReSolvedCentralDifferences) {
  // A knuckle bound at 98° holds the finger back (active; the free optimum is at 100.5°), the
  // tip on the surface (rhs 0).
  const std::string start = R"({"list": [{"joints_deg": {"turntable": -120, "knuckle": 80,
                                                         "middle joint": 40}}]})";
  const double max_deg = 98.0;
  const Study base(Parse(FingerRun(0.0, max_deg, start)));
  const CaseResult r = base.Solve(0);
  ASSERT_EQ(r.status, "optimum");
  double d_rhs = 0.0, d_max = 0.0;
  bool bound_active = false;
  for (const Sensitivity& s : r.sensitivities) {
    if (s.constraint == "tip on the surface") d_rhs = s.derivative;
    if (s.constraint == "bound knuckle" && s.wrt == "max_deg") {
      d_max = s.derivative;
      bound_active = s.active;
    }
  }
  ASSERT_TRUE(bound_active);
  auto objective = [&](double rhs, double hi) {
    const Study moved(Parse(FingerRun(rhs, hi, start)));
    const CaseResult m = moved.Solve(0);
    EXPECT_EQ(m.status, "optimum");
    return m.objective;
  };
  // Steps: large enough that the re-solves' own error (relative KKT 1e-9) is negligible in the
  // difference, small enough that the optimum's curvature in b leaves ≤ 1e-5 relative.
  const double eps = 1e-5, eps_deg = 1e-3;
  const double fd_rhs = (objective(eps, max_deg) - objective(-eps, max_deg)) / (2 * eps);
  const double fd_max =
      (objective(0.0, max_deg + eps_deg) - objective(0.0, max_deg - eps_deg)) / (2 * eps_deg);
  std::printf(
      "dF/d(rhs): reported %.9g, re-solved %.9g; dF/d(max_deg): reported %.9g, "
      "re-solved %.9g\n",
      d_rhs, fd_rhs, d_max, fd_max);
  EXPECT_NEAR(d_rhs, fd_rhs, 1e-4 * std::abs(fd_rhs));
  EXPECT_NEAR(d_max, fd_max, 1e-4 * std::abs(fd_max));
  EXPECT_GT(d_max, 0.0);  // the bound holds the finger back from a better pose
}

TEST(StudyTest, AGridPointSolvesLikeARunWithItsRightHandSide) {
  // The rhs is per-solve data: case k of a grid over the surface constraint's rhs is the run
  // with that rhs written in the file.
  const std::string start = R"({"list": [{"joints_deg": {"turntable": -120, "knuckle": 80,
                                                         "middle joint": 40}}]})";
  std::string text = FingerRun(0.0, 150.0, start);
  text.replace(text.find("\"starts\""), 8,
               R"("grid": [{"constraint": "tip on the surface", "values": [0, 0.01]}], "starts")");
  const Study grid(Parse(text));
  ASSERT_EQ(grid.num_cases(), 2);
  const CaseResult a = grid.Solve(1);
  ASSERT_EQ(a.grid.size(), 1u);
  EXPECT_EQ(a.grid[0].first, "tip on the surface row 0");
  EXPECT_EQ(a.grid[0].second, 0.01);
  const Study direct(Parse(FingerRun(0.01, 150.0, start)));
  const CaseResult b = direct.Solve(0);
  EXPECT_EQ(a.status, "optimum");
  EXPECT_EQ(a.objective, b.objective);
  EXPECT_EQ(a.q, b.q);
}

TEST(StudyTest, OneAndTwoThreadsGiveIdenticalResults) {
  const Study study(Parse(FingerRun(0.0, 150.0, R"({"random": 6, "seed": 11})")));
  std::vector<int> all(static_cast<size_t>(study.num_cases()));
  for (int i = 0; i < study.num_cases(); ++i) all[static_cast<size_t>(i)] = i;
  RunnerOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = WithoutTimings(ResultFile(study, RunCases(study, all, one)));
  const auto b = WithoutTimings(ResultFile(study, RunCases(study, all, two)));
  EXPECT_EQ(a.dump(), b.dump());
  EXPECT_EQ(a["optima"].get<int>(), study.num_cases());
}

TEST(StudyTest, ResumeKeepsJournalledCasesAndSolvesTheRest) {
  const Study study(Parse(FingerRun(0.0, 150.0, R"({"random": 3, "seed": 2})")));
  const std::string journal = ::testing::TempDir() + "/study_resume.partial";
  {
    // Case 1 as journalled by an earlier run (a marker objective), then a torn line.
    std::ofstream out(journal);
    nlohmann::json done = study.ToJson(CaseResult{});
    done["case"] = 1;
    done["status"] = "optimum";
    done["objective"] = 42.0;
    out << done.dump() << "\n{\"case\": 2, \"stat";
  }
  RunnerOptions o;
  o.resume_from = {journal};
  int solved = 0;
  o.progress = [&](int, int, const nlohmann::json&) { ++solved; };
  const auto results = RunCases(study, {0, 1, 2}, o);
  EXPECT_EQ(solved, 2);  // cases 0 and 2 (the torn line does not count)
  EXPECT_EQ(results.at(1)["objective"].get<double>(), 42.0);
  EXPECT_EQ(results.at(2)["status"].get<std::string>(), "optimum");
  std::filesystem::remove(journal);
}

TEST(StudyTest, AnInfeasibleSetIsReportedAsInfeasibleWithItsViolatedConstraint) {
  // The tip on a plane 2 m up: beyond the finger's 0.75 m reach.
  const Study study(Parse(R"({
    "scene": "three_link_finger.json",
    "objective": {"terms": [{"measure": "dexterity",
        "end_effector": {"body": "distal", "point": [0, 0, 0.2]},
        "joints": ["turntable", "knuckle", "middle joint"]}]},
    "constraints": [{"name": "tip up high", "type": "plane",
                     "at": {"body": "distal", "point": [0, 0, 0.2]},
                     "origin": [0, 0, 2], "normal": [0, 0, 1]}],
    "starts": {"list": [{"joints_deg": {"knuckle": 30, "middle joint": 20}}]},
    "solver": {"max_iterations": 80}})"));
  const CaseResult r = study.Solve(0);
  EXPECT_EQ(r.status, "infeasible");
  EXPECT_FALSE(r.converged);
  ASSERT_FALSE(r.violated.empty());
  // Named, at the least-violation point with the mechanism intact: the tip as high as it goes
  // (0.75 m up at most), 1.25 m short.
  ASSERT_EQ(r.violated.size(), 1u);
  EXPECT_EQ(r.violated[0].rfind("tip up high: off by 1.2", 0), 0u) << r.violated[0];
  EXPECT_NEAR(r.violation, 1.25, 1e-6);
}

}  // namespace
}  // namespace tangent::design
