// Four-bar warm solves (seed 001 Fig. 7, the grasp dragged along the path of
// testing/fourbar.h) by our augmented-Lagrangian solver, IPOPT and NLopt SLSQP on the
// identical problem: same objective (least astonishment + grasp), same equality constraints
// (joints and unit quaternions), same starting point at every step (our previous solution).
// IPOPT gets the exact Lagrangian Hessian from the same term Hessians; SLSQP its own BFGS.
//
// Google Benchmark entries (one warm solve per iteration, cycling through the path):
//   fourbar_warm_solve/ours_al, fourbar_warm_solve/ipopt, fourbar_warm_solve/nlopt_slsqp
// then a table over the whole path: time per solve (median, p99), worst violation, and the
// largest difference of objective and grasp position from ours; and the ratios.
// --steps=N sets the path length (default 1000).

#include <benchmark/benchmark.h>
#include <nlopt.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "optimizer/evaluator.h"
#include "optimizer/solver.h"
#include "testing/fourbar.h"
#include "testing/ipopt_problem.h"

namespace tangent::optimizer {
namespace {

int g_steps = 1000;

// The benchmark problem: the four-bar, its goal handle, and the starting points (our solution
// chain along the path: start[k] is the warm start for step k).
struct Setup {
  testing::FourBar fb;
  std::shared_ptr<PositionGoalTerm> goal;
  Problem problem;
  std::vector<Eigen::VectorXd> start;
  std::vector<Eigen::VectorXd> ours;  // our solution at each step
  Setup() : problem(fb.MakeProblem(testing::FourBar::PathPoint(0), &goal)) {
    Solver s(problem);
    Eigen::VectorXd q = fb.mechanism.InitialCoordinates();
    s.Solve(&q);
    for (int k = 1; k <= g_steps; ++k) {
      start.push_back(q);
      SetGoalTarget(s.data(), *goal, testing::FourBar::PathPoint(k));
      s.Solve(&q);
      ours.push_back(q);
    }
  }
};

Setup& GetSetup() {
  static Setup s;
  return s;
}

// ---- IPOPT ----------------------------------------------------------------------------------

// The shared adapter (testing/ipopt_problem.h): exact Lagrangian Hessian from the terms.
struct IpoptPeer {
  testing::IpoptSolver solver;
  explicit IpoptPeer(const Problem& p) : solver(p) {}
  ProblemData& data() { return solver.data(); }
  Eigen::VectorXd Solve(const Eigen::VectorXd& q0) { return solver.Solve(q0).q; }
};

// ---- NLopt SLSQP ----------------------------------------------------------------------------

struct Slsqp {
  const Problem& p;
  ProblemEvaluator ev;
  Eigen::VectorXd q0, q, grad;
  Eigen::MatrixXd M;
  nlopt_opt opt;
  ProblemData& data() { return ev.data(); }
  explicit Slsqp(const Problem& problem) : p(problem), ev(problem) {
    const int n = p.mechanism().num_coordinates();
    opt = nlopt_create(NLOPT_LD_SLSQP, static_cast<unsigned>(n));
    nlopt_set_min_objective(opt, &Objective, this);
    std::vector<double> tol(static_cast<size_t>(p.num_equality_rows()), 1e-12);
    nlopt_add_equality_mconstraint(opt, static_cast<unsigned>(p.num_equality_rows()), &Constraints,
                                   this, tol.data());
    nlopt_set_ftol_rel(opt, 1e-16);
    nlopt_set_xtol_rel(opt, 1e-12);
    nlopt_set_maxeval(opt, 2000);
    grad.setZero(n);
  }
  ~Slsqp() { nlopt_destroy(opt); }
  static double Objective(unsigned n, const double* x, double* g, void* data) {
    auto* s = static_cast<Slsqp*>(data);
    s->q = Eigen::Map<const Eigen::VectorXd>(x, n);
    s->ev.Evaluate(s->q);
    if (g) {
      s->ev.ObjectiveGradient(s->q, s->q0, s->M, &s->grad);
      std::copy(s->grad.data(), s->grad.data() + n, g);
    }
    return s->ev.Objective(s->q, s->q0, s->M);
  }
  static void Constraints(unsigned m, double* c, unsigned n, const double* x, double* g,
                          void* data) {
    auto* s = static_cast<Slsqp*>(data);
    s->q = Eigen::Map<const Eigen::VectorXd>(x, n);
    s->ev.Evaluate(s->q);
    std::copy(s->ev.c_e().data(), s->ev.c_e().data() + m, c);
    if (g) {
      for (unsigned i = 0; i < m; ++i)
        for (unsigned j = 0; j < n; ++j) g[i * n + j] = s->ev.J_e()(i, j);
    }
  }
  Eigen::VectorXd Solve(const Eigen::VectorXd& start) {
    q0 = start;
    p.mechanism().Metric(q0, &M);
    Eigen::VectorXd x = start;
    double f = 0;
    nlopt_optimize(opt, x.data(), &f);
    return x;
  }
};

// ---- Benchmarks -----------------------------------------------------------------------------

// `data`: the solver's own (its goal target).
template <class Solve>
void Cycle(benchmark::State& state, ProblemData& data, Solve&& solve) {
  Setup& s = GetSetup();
  size_t k = 0;
  for (auto _ : state) {
    SetGoalTarget(data, *s.goal, testing::FourBar::PathPoint(static_cast<int>(k) + 1));
    benchmark::DoNotOptimize(solve(s.start[k]));
    k = (k + 1) % s.start.size();
  }
}

void BM_Ours(benchmark::State& state) {
  Setup& s = GetSetup();
  Solver solver(s.problem);
  Eigen::VectorXd q;
  Cycle(state, solver.data(), [&](const Eigen::VectorXd& q0) {
    q = q0;
    return solver.Solve(&q).iterations;
  });
}
void BM_Ipopt(benchmark::State& state) {
  IpoptPeer ipopt(GetSetup().problem);
  Cycle(state, ipopt.data(), [&](const Eigen::VectorXd& q0) { return ipopt.Solve(q0)[0]; });
}
void BM_Slsqp(benchmark::State& state) {
  Slsqp slsqp(GetSetup().problem);
  Cycle(state, slsqp.data(), [&](const Eigen::VectorXd& q0) { return slsqp.Solve(q0)[0]; });
}

// Whole path per solver, identical starting points: per-solve times and accuracy against ours.
struct PathResult {
  std::vector<double> us;
  double worst_violation = 0, worst_objective_diff = 0, worst_grasp_diff = 0;
};

template <class Solve>
PathResult RunPath(ProblemData& data, Solve&& solve) {
  Setup& s = GetSetup();
  PathResult r;
  ProblemEvaluator ev(s.problem);
  std::vector<BodyPose> a, b;
  Eigen::MatrixXd M;
  for (size_t k = 0; k < s.start.size(); ++k) {
    SetGoalTarget(data, *s.goal, testing::FourBar::PathPoint(static_cast<int>(k) + 1));
    SetGoalTarget(ev.data(), *s.goal, testing::FourBar::PathPoint(static_cast<int>(k) + 1));
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::VectorXd q = solve(s.start[k]);
    r.us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    ev.Evaluate(q);
    r.worst_violation = std::max(r.worst_violation, ev.c_e().cwiseAbs().maxCoeff());
    s.problem.mechanism().Metric(s.start[k], &M);
    const double fq = ev.Objective(q, s.start[k], M);
    ev.Evaluate(s.ours[k]);
    const double fo = ev.Objective(s.ours[k], s.start[k], M);
    r.worst_objective_diff = std::max(r.worst_objective_diff, std::abs(fq - fo));
    s.problem.mechanism().Poses(q, &a);
    s.problem.mechanism().Poses(s.ours[k], &b);
    r.worst_grasp_diff = std::max(
        r.worst_grasp_diff,
        (a[s.fb.coupler].Point(s.fb.grasp.point) - b[s.fb.coupler].Point(s.fb.grasp.point)).norm());
  }
  std::sort(r.us.begin(), r.us.end());
  return r;
}

double Percentile(const std::vector<double>& sorted, double p) {
  return sorted[std::min(sorted.size() - 1,
                         static_cast<size_t>(p * static_cast<double>(sorted.size())))];
}

void Report() {
  Setup& s = GetSetup();
  Solver solver(s.problem);
  IpoptPeer ipopt(s.problem);
  Slsqp slsqp(s.problem);
  Eigen::VectorXd q;
  // Ours twice: the first pass warms caches; report the second.
  RunPath(solver.data(), [&](const Eigen::VectorXd& q0) {
    q = q0;
    solver.Solve(&q);
    return q;
  });
  const PathResult ours = RunPath(solver.data(), [&](const Eigen::VectorXd& q0) {
    q = q0;
    solver.Solve(&q);
    return q;
  });
  const PathResult ip =
      RunPath(ipopt.data(), [&](const Eigen::VectorXd& q0) { return ipopt.Solve(q0); });
  const PathResult sl =
      RunPath(slsqp.data(), [&](const Eigen::VectorXd& q0) { return slsqp.Solve(q0); });
  std::printf("\nFour-bar warm solves along the %zu-step path (identical starting points), us:\n",
              s.start.size());
  std::printf("%-12s %10s %10s %14s %16s %14s\n", "solver", "median", "p99", "worst viol.",
              "obj. diff", "grasp diff m");
  for (const auto& [name, r] : {std::pair<const char*, const PathResult*>{"ours_al", &ours},
                                {"ipopt", &ip},
                                {"nlopt_slsqp", &sl}}) {
    std::printf("%-12s %10.2f %10.2f %14.1e %16.1e %14.1e\n", name, Percentile(r->us, 0.5),
                Percentile(r->us, 0.99), r->worst_violation, r->worst_objective_diff,
                r->worst_grasp_diff);
  }
  const double p99 = Percentile(ours.us, 0.99), med = Percentile(ours.us, 0.5);
  std::printf("\nTargets: p99 <= 20 us with violation <= 1e-10: %.2f us, %.1e — %s\n", p99,
              ours.worst_violation, p99 <= 20 && ours.worst_violation <= 1e-10 ? "met" : "NOT MET");
  std::printf("  vs IPOPT (median): %.1fx faster (target >= 50x) — %s\n",
              Percentile(ip.us, 0.5) / med, Percentile(ip.us, 0.5) / med >= 50 ? "met" : "NOT MET");
  std::printf("  vs NLopt SLSQP (median): %.1fx faster (target >= 2.5x) — %s\n",
              Percentile(sl.us, 0.5) / med,
              Percentile(sl.us, 0.5) / med >= 2.5 ? "met" : "NOT MET");
  const double ratio = Percentile(ip.us, 0.5) / med;
  std::printf(
      "  Issue 35: median <= 10 us and >= 150x IPOPT in the same run: %.2f us, %.1fx — %s\n", med,
      ratio, med <= 10.0 && ratio >= 150.0 ? "met" : "NOT MET");
  std::printf(
      "  same optimum within 1e-8 (grasp position vs IPOPT, exact Hessian, tol 1e-10): %.1e — %s\n"
      "  (SLSQP's BFGS stops %.1e from both at ftol_rel 1e-16, xtol_rel 1e-12: its own limit)\n",
      ip.worst_grasp_diff, ip.worst_grasp_diff <= 1e-8 ? "met" : "NOT MET", sl.worst_grasp_diff);
}

}  // namespace
}  // namespace tangent::optimizer

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--steps=", 8) == 0)
      tangent::optimizer::g_steps = std::atoi(argv[i] + 8);
  }
  using namespace tangent::optimizer;
  benchmark::RegisterBenchmark("fourbar_warm_solve/ours_al", BM_Ours);
  benchmark::RegisterBenchmark("fourbar_warm_solve/ipopt", BM_Ipopt);
  benchmark::RegisterBenchmark("fourbar_warm_solve/nlopt_slsqp", BM_Slsqp);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  Report();
  benchmark::Shutdown();
  return 0;
}
