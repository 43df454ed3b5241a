// Design over a range of motion: the replica of a scene at K configurations, the worst-case
// objective (its value bounds and its gradient against central differences), the four-bar
// ground-link example against IPOPT, its sensitivities against re-solves, and the run file's
// bad input.

#include "design/configurations.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <numbers>

#include "design/study.h"
#include "testing/ipopt_problem.h"

namespace tangent::design {
namespace {

using ::testing::HasSubstr;

const std::string kScenes = TANGENT_SCENES_DIR;
const std::string kExample = "fourbar_force_transmission.run.json";
constexpr double kDeg = std::numbers::pi / 180.0;

nlohmann::json ExampleJson() {
  std::ifstream in(kScenes + "/" + kExample);
  return nlohmann::json::parse(in);
}

RunSpec FromJson(const nlohmann::json& j) { return ParseRun(j.dump(), "run.json", kScenes); }

TEST(ConfigurationsTest, TheReplicaSharesTheDesignSideAndCopiesTheRest) {
  const RunSpec run = LoadRun(kScenes + "/" + kExample);
  ASSERT_TRUE(run.configurations);
  const ConfigurationsSpec& c = *run.configurations;
  const server::Scene& base = *c.base;
  const server::Scene& s = *run.scene;
  ASSERT_EQ(c.size(), 7);
  // ground and the rocker mount once; crank, coupler and rocker once per configuration.
  const int mount = base.BodyIndex("rocker mount"), crank = base.BodyIndex("crank");
  EXPECT_TRUE(c.shared_body[static_cast<size_t>(mount)]);
  EXPECT_FALSE(c.shared_body[static_cast<size_t>(crank)]);
  EXPECT_EQ(s.mechanism.num_bodies(), 2 + 3 * 7);
  EXPECT_EQ(c.Body(0, mount), c.Body(6, mount));
  EXPECT_NE(c.Body(0, crank), c.Body(6, crank));
  EXPECT_EQ(s.mechanism.body(c.Body(2, crank)).name, "crank@3");
  // The ground link once (a design joint), the other four joints per copy.
  EXPECT_EQ(s.joints.size(), 1u + 4u * 7u);
  EXPECT_EQ(s.joints[static_cast<size_t>(c.Joint(3, base.JointIndex("rocker")))].name, "rocker@4");
  // The design joint moved to the replica's index, the bound copied per configuration, one
  // configuration equality per copy, the configuration joint at its value in every start.
  ASSERT_EQ(run.design_joints.size(), 1u);
  EXPECT_EQ(s.joints[static_cast<size_t>(run.design_joints[0].joint)].name, "ground link");
  EXPECT_EQ(run.bounds.size(), 7u);
  ASSERT_EQ(run.constraints.size(), 7u);
  EXPECT_EQ(run.constraints[0].name, "configuration 1: crank at -150 deg");
  // Gathering copy k's coordinates reads exactly its bodies' (and the shared ones').
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(s.mechanism.num_coordinates(), 0, 1);
  const Eigen::VectorXd q3 = c.Gather(3, q);
  ASSERT_EQ(q3.size(), base.mechanism.num_coordinates());
  for (int b = 0; b < base.mechanism.num_bodies(); ++b) {
    if (base.mechanism.offset(b) < 0) continue;
    EXPECT_EQ(q3.segment<7>(base.mechanism.offset(b)),
              q.segment<7>(s.mechanism.offset(c.Body(3, b))));
  }
  Eigen::VectorXd g = Eigen::VectorXd::Zero(q.size());
  c.ScatterAdd(3, Eigen::VectorXd::Ones(q3.size()), &g);
  c.ScatterAdd(4, Eigen::VectorXd::Ones(q3.size()), &g);
  EXPECT_EQ(g.sum(), 2.0 * static_cast<double>(q3.size()));
  EXPECT_EQ(g[s.mechanism.offset(c.Body(0, mount))], 2.0);  // shared: both copies add
}

TEST(ConfigurationsTest, WorstCaseLiesWithinItsToleranceOfTheExactWorstCase) {
  for (const bool lowest : {true, false}) {
    for (const double tolerance : {1e-3, 0.1}) {
      ConfigurationsSpec c;
      c.values = {0, 1, 2, 3, 4};
      c.tolerance = tolerance;
      const WorstCase w({}, &c, lowest);
      for (const Eigen::VectorXd& F :
           {Eigen::VectorXd(Eigen::Vector<double, 5>(3, 1, 2, 5, 4)),
            Eigen::VectorXd(Eigen::Vector<double, 5>(2, 2, 2, 2, 2)),
            Eigen::VectorXd(Eigen::Vector<double, 5>(1e3, 0, 1e-4, 7, 0))}) {
        const double ks = w.Aggregate(F);
        if (lowest) {
          EXPECT_GE(ks, F.minCoeff() - 1e-12);
          EXPECT_LE(ks, F.minCoeff() + tolerance + 1e-12);
        } else {
          EXPECT_LE(ks, F.maxCoeff() + 1e-12);
          EXPECT_GE(ks, F.maxCoeff() - tolerance - 1e-12);
        }
      }
      // All equal: exact.
      EXPECT_NEAR(w.Aggregate(Eigen::VectorXd::Constant(5, 2.5)), 2.5, 1e-15);
    }
  }
}

TEST(ConfigurationsTest, WorstCaseGradientMatchesCentralDifferences) {
  // A loose tolerance so that every copy weighs in the gradient (a sharp one is dominated by
  // the worst copy), at the example's assembled start and at a design the worst cases tie near.
  nlohmann::json j = ExampleJson();
  j["configurations"]["tolerance"] = 0.5;
  for (const double length : {0.02, 0.045}) {
    j["starts"] = {{"list", {{{"joints_m", {{"ground link", length}}}}}}};
    const Study study(FromJson(j));
    bool ok = false;
    const Eigen::VectorXd q = study.StartConfiguration(0, &ok);
    ASSERT_TRUE(ok);
    ASSERT_EQ(study.problem().design_objectives().size(), 1u);
    const optimizer::DesignObjective& f = *study.problem().design_objectives()[0].f;
    Eigen::VectorXd g;
    f.Gradient(q, &g);
    ASSERT_EQ(g.size(), q.size());
    const double h = 1e-6;
    double worst = 0.0;
    for (int i = 0; i < q.size(); ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double fd = (f.Value(qp) - f.Value(qm)) / (2 * h);
      worst = std::max(worst, std::abs(fd - g[i]) / std::max(1.0, std::abs(g[i])));
    }
    std::printf("ground link %.3f m: |g − FD| / max(1, |g|) ≤ %.2e over %d coordinates\n", length,
                worst, static_cast<int>(q.size()));
    EXPECT_LT(worst, 1e-6);
  }
}

TEST(ConfigurationsTest, FourBarExampleReachesIpoptsOptimumFromEveryStart) {
  const Study study(LoadRun(kScenes + "/" + kExample));
  optimizer::testing::IpoptSolver ipopt(study.problem());
  for (int i = 0; i < study.num_cases(); ++i) {
    const CaseResult ours = study.Solve(i);
    bool ok = false;
    const Eigen::VectorXd q0 = study.StartConfiguration(i, &ok);
    ASSERT_TRUE(ok) << i;
    study.PrepareData(i, q0, &ipopt.data());
    const optimizer::testing::IpoptResult ref = ipopt.Solve(q0);
    const double theirs = study.Objective(ref.q);
    std::printf("case %d: ours %.10f (%s, %d iterations, %.1f ms), IPOPT %.10f (%s, %d)\n", i,
                ours.objective, ours.status.c_str(), ours.iterations, ours.time_ms, theirs,
                ref.solved ? "solved" : "failed", ref.iterations);
    EXPECT_EQ(ours.status, "optimum") << i;
    EXPECT_LE(ours.violation, study.run().constraint_tolerance) << i;
    ASSERT_TRUE(ref.solved) << i;
    EXPECT_NEAR(ours.objective, theirs, 1e-6 * std::abs(theirs)) << i;
    // The exact worst case is reported beside the smooth one, within the tolerance below it.
    ASSERT_FALSE(ours.measures.empty());
    EXPECT_EQ(ours.measures.back().first, "worst case");
    EXPECT_LE(ours.measures.back().second, ours.objective);
    EXPECT_GE(ours.measures.back().second, ours.objective - 1e-3);
  }
}

TEST(ConfigurationsTest, SensitivitiesMatchReSolvedCentralDifferences) {
  // dF*/dθ_1 (the first configuration's crank angle, per radian) and dF*/d(max) of the ground
  // link (per metre, active: the worst case improves as the ground link lengthens) against
  // re-solves with each moved by ±ε.
  auto solve = [](double first_deg, double max) {
    nlohmann::json j = ExampleJson();
    j["configurations"].erase("range_deg");
    j["configurations"]["values_deg"] = {first_deg, -130, -110, -90, -70, -50, -30};
    j["design"][0]["max"] = max;
    j["starts"] = {{"list", {{{"joints_m", {{"ground link", 0.035}}}}}}};
    const CaseResult r = Study(FromJson(j)).Solve(0);
    EXPECT_EQ(r.status, "optimum");
    return r;
  };
  const CaseResult r = solve(-150, 0.05);
  double d_theta = 0.0, d_max = 0.0;
  for (const Sensitivity& s : r.sensitivities) {
    if (s.constraint == "configuration 1: crank at -150 deg") d_theta = s.derivative;
    if (s.constraint == "design ground link" && s.wrt == "max") d_max = s.derivative;
  }
  const double eps_deg = 1e-3, eps = 1e-5;
  const double fd_theta =
      (solve(-150 + eps_deg, 0.05).objective - solve(-150 - eps_deg, 0.05).objective) /
      (2 * eps_deg * kDeg);
  const double fd_max =
      (solve(-150, 0.05 + eps).objective - solve(-150, 0.05 - eps).objective) / (2 * eps);
  std::printf(
      "dF/dtheta_1: reported %.9g, re-solved %.9g; dF/d(max): reported %.9g, "
      "re-solved %.9g\n",
      d_theta, fd_theta, d_max, fd_max);
  EXPECT_GT(d_max, 0.0);
  EXPECT_NEAR(d_theta, fd_theta, 1e-4 * std::abs(fd_theta));
  EXPECT_NEAR(d_max, fd_max, 1e-4 * std::abs(fd_max));
}

std::string ErrorOf(const nlohmann::json& j) {
  try {
    FromJson(j);
  } catch (const RunError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << j.dump();
  return "";
}

TEST(ConfigurationsTest, BadConfigurationsAreRejectedNamingTheItem) {
  nlohmann::json j = ExampleJson();
  j["configurations"].erase("tolerance");
  EXPECT_THAT(ErrorOf(j), HasSubstr("run.json: /configurations: give \"tolerance\""));
  j = ExampleJson();
  j["configurations"]["tolerance"] = -1;
  EXPECT_THAT(ErrorOf(j), HasSubstr("/configurations/tolerance"));
  j = ExampleJson();
  j["configurations"]["joint"] = "cranck";
  EXPECT_THAT(ErrorOf(j), HasSubstr("/configurations/joint: no joint named \"cranck\""));
  j = ExampleJson();
  j["configurations"]["values"] = {0.1};
  EXPECT_THAT(ErrorOf(j), HasSubstr("a revolute joint's configurations are angles"));
  j = ExampleJson();
  j["configurations"]["range_deg"] = {-30, -150, 7};
  EXPECT_THAT(ErrorOf(j), HasSubstr("/configurations/range_deg: empty or inverted range"));
  j = ExampleJson();
  j["configurations"].erase("range_deg");
  j["configurations"]["values_deg"] = {-90, 200};
  EXPECT_THAT(ErrorOf(j), HasSubstr("angles must lie within [-180, 180]"));
  j = ExampleJson();
  j["configurations"]["joint"] = "ground link";
  j["configurations"].erase("range_deg");
  j["configurations"]["values"] = {0.01, 0.02};
  EXPECT_THAT(ErrorOf(j), HasSubstr("a design joint cannot be the configuration joint"));
  j = ExampleJson();
  j["bounds"].push_back({{"joint", "crank"}, {"min_deg", -160}, {"max_deg", -20}});
  EXPECT_THAT(ErrorOf(j), HasSubstr("/configurations/joint: is bounded too"));
  j = ExampleJson();
  j["starts"]["list"][1]["joints_deg"] = {{"crank", -90}};
  EXPECT_THAT(ErrorOf(j), HasSubstr("/starts/list/1: sets the configuration joint \"crank\""));
  j = ExampleJson();
  j["constraints"] = {{{"name", "tip"},
                       {"type", "plane"},
                       {"at", {{"body", "coupler"}}},
                       {"origin", {0, 0, 0}},
                       {"normal", {0, 0, 1}}}};
  EXPECT_THAT(ErrorOf(j), HasSubstr("/constraints: cannot be combined with \"configurations\""));
  // A design joint that would move with the configurations: the finger's middle link.
  std::ifstream in(kScenes + "/three_link_finger_design.run.json");
  j = nlohmann::json::parse(in);
  j.erase("constraints");
  j["configurations"] = {{"joint", "turntable"}, {"values_deg", {-30, 30}}, {"tolerance", 1e-3}};
  j["starts"] = {{"list", {{{"joints_m", {{"middle length", 0.0}}}}}}};
  EXPECT_THAT(ErrorOf(j), HasSubstr("design joint \"middle length\" would move with the "
                                    "configurations"));
}

}  // namespace
}  // namespace tangent::design
