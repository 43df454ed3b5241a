// Offline design solves (tangent-opt's cases) against IPOPT, and how a sweep scales with threads.
//
//  1. Per example run file (scenes/*.run.json): every case solved from its assembled start by
//     our design mode and by IPOPT (limited-memory Hessian: the design objectives have gradients
//     only) in the same process, each timed over --reps repetitions (median); the optimum each
//     reaches. Assembly of the start is not timed (it is the same for both).
//  2. A sweep of --sweep seeded random starts of the finger run on 1 and on 2 threads (one shared
//     problem): wall time and speed-up, and whether the results are identical. (256 by default:
//     64 cases are over in 70 ms on two threads, too short against this shared machine's noise.)
//
// Usage: design_bench [--reps N] [--sweep N] [--scenes DIR] [--only RUN.json] (--sweep 0: none)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "design/runner.h"
#include "design/study.h"
#include "testing/ipopt_problem.h"

namespace {

using tangent::design::Study;
using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double Ms(Clock::time_point a, Clock::time_point b) {
  return 1e3 * std::chrono::duration<double>(b - a).count();
}

struct Row {
  std::string run;
  int cases = 0, ours_optima = 0, ipopt_solved = 0, same = 0;
  double ours_ms = 0.0, ipopt_ms = 0.0;
};

Row Compare(const std::string& path, int reps) {
  const Study study(tangent::design::LoadRun(path));
  tangent::optimizer::testing::IpoptSolver ipopt(study.problem());
  Row row;
  row.run = path.substr(path.find_last_of('/') + 1);
  std::vector<double> ours_ms, ipopt_ms;
  for (int i = 0; i < study.num_cases(); ++i) {
    bool ok = false;
    const Eigen::VectorXd q0 = study.StartConfiguration(i, &ok);
    if (!ok) continue;
    ++row.cases;
    tangent::optimizer::SolverOptions o;
    o.design.enabled = true;
    o.design.relative_kkt_tolerance = study.run().relative_kkt_tolerance;
    o.max_iterations = study.run().max_iterations;
    o.constraint_tolerance = study.run().constraint_tolerance;
    Eigen::VectorXd q;
    tangent::optimizer::SolveStats st;
    std::vector<double> a, b;
    tangent::optimizer::testing::IpoptResult ref;
    for (int r = 0; r < reps; ++r) {
      const auto t0 = Clock::now();
      tangent::optimizer::Solver solver(study.problem(), o);
      study.PrepareData(i, q0, &solver.data());
      q = q0;
      st = solver.Solve(&q);
      const auto t1 = Clock::now();
      study.PrepareData(i, q0, &ipopt.data());
      ref = ipopt.Solve(q0);
      const auto t2 = Clock::now();
      a.push_back(Ms(t0, t1));
      b.push_back(Ms(t1, t2));
    }
    ours_ms.push_back(Median(a));
    ipopt_ms.push_back(Median(b));
    row.ours_optima += st.converged;
    row.ipopt_solved += ref.solved;
    const double f_ours = study.Objective(q), f_ipopt = study.Objective(ref.q);
    row.same +=
        st.converged && ref.solved && std::abs(f_ours - f_ipopt) <= 1e-6 * std::abs(f_ipopt);
  }
  row.ours_ms = Median(ours_ms);
  row.ipopt_ms = Median(ipopt_ms);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 5, sweep = 256;
  std::string scenes = TANGENT_SCENES_DIR, only;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--reps")) reps = std::max(1, std::atoi(argv[i + 1]));
    if (!std::strcmp(argv[i], "--sweep")) {
      sweep = std::atoi(argv[i + 1]);
      if (sweep != 0) sweep = std::max(2, sweep);
    }
    if (!std::strcmp(argv[i], "--scenes")) scenes = argv[i + 1];
    if (!std::strcmp(argv[i], "--only")) only = argv[i + 1];
  }
  std::printf("Design solves against IPOPT (same process, same starts; median of %d reps):\n",
              reps);
  std::printf("%-36s %6s %8s %8s %6s %10s %10s %8s\n", "run", "cases", "ours ok", "ipopt ok",
              "same", "ours ms", "ipopt ms", "ratio");
  for (const char* run :
       {"three_link_finger.run.json", "fourbar_dexterity.run.json",
        "three_link_finger_design.run.json", "fourbar_force_transmission.run.json"}) {
    if (!only.empty() && only != run) continue;
    const Row r = Compare(scenes + "/" + run, reps);
    std::printf("%-36s %6d %8d %8d %6d %10.2f %10.2f %7.2fx\n", r.run.c_str(), r.cases,
                r.ours_optima, r.ipopt_solved, r.same, r.ours_ms, r.ipopt_ms,
                r.ipopt_ms / std::max(r.ours_ms, 1e-9));
  }

  if (sweep == 0) return 0;
  // The sweep: the finger run with `sweep` random starts, on 1 and 2 threads.
  char text[1536];
  std::snprintf(text, sizeof(text), R"({
    "scene": "three_link_finger.json",
    "objective": {"terms": [{"measure": "dexterity",
        "end_effector": {"body": "distal", "point": [0, 0, 0.2]},
        "joints": ["turntable", "knuckle", "middle joint"]}]},
    "constraints": [{"name": "tip on the surface", "type": "point_on_surface",
                     "at": {"body": "distal", "point": [0, 0, 0.2]}, "surface": "terrain"}],
    "bounds": [{"joint": "knuckle", "min_deg": 10, "max_deg": 150},
               {"joint": "middle joint", "min_deg": 5, "max_deg": 150}],
    "starts": {"random": %d, "seed": 1}})",
                sweep);
  const Study study(tangent::design::ParseRun(text, "sweep", scenes));
  std::vector<int> all(static_cast<size_t>(study.num_cases()));
  for (int i = 0; i < study.num_cases(); ++i) all[static_cast<size_t>(i)] = i;
  std::string first;
  double wall[2] = {0, 0};
  for (int threads : {1, 2}) {
    tangent::design::RunnerOptions o;
    o.threads = threads;
    const auto t0 = Clock::now();
    const auto results = tangent::design::RunCases(study, all, o);
    wall[threads - 1] = Ms(t0, Clock::now());
    const std::string dump =
        tangent::design::WithoutTimings(tangent::design::ResultFile(study, results)).dump();
    if (threads == 1) first = dump;
    std::printf("sweep of %d cases on %d thread%s: %.1f ms%s\n", study.num_cases(), threads,
                threads > 1 ? "s" : "", wall[threads - 1],
                threads > 1 ? (dump == first ? " (results identical)" : " (RESULTS DIFFER)") : "");
  }
  std::printf("Thread speed-up 1 -> 2: %.2fx (target >= 1.8x on 2 free cores)\n",
              wall[0] / std::max(wall[1], 1e-9));
  return 0;
}
