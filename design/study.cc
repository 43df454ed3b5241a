#include "design/study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "optimizer/contacts.h"
#include "optimizer/goals.h"
#include "optimizer/joints.h"

namespace tangent::design {

namespace {

using optimizer::DesignObjective;
using optimizer::Problem;

constexpr double kDeg = std::numbers::pi / 180.0;

// −f, for a measure minimized (design objectives are maximized with a positive weight).
class Negated final : public DesignObjective {
 public:
  explicit Negated(std::shared_ptr<const DesignObjective> f) : f_(std::move(f)) {}
  std::string name() const override { return "-" + f_->name(); }
  double Value(const Eigen::VectorXd& q) const override { return -f_->Value(q); }
  void Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* g) const override {
    f_->Gradient(q, g);
    *g = -*g;
  }

 private:
  std::shared_ptr<const DesignObjective> f_;
};

optimizer::DexterityMeasure MeasureOf(const std::string& m) {
  if (m == "inverse_condition") return optimizer::DexterityMeasure::kInverseCondition;
  if (m == "force_transmission") return optimizer::DexterityMeasure::kForceTransmission;
  return optimizer::DexterityMeasure::kDexterity;
}

double Measure(const optimizer::Dexterity::Measures& m, const std::string& name) {
  if (name == "inverse_condition") return m.inverse_condition;
  if (name == "force_transmission") return m.force_transmission;
  return m.dexterity;
}

// The parameters of the point of `surface` nearest to x_W, over a grid of samples (a seed for
// the tracked closest point).
Eigen::Vector2d NearestSample(const nurbs::NurbsSurface& surface, const contact::BodyPose& pose,
                              const Eigen::Vector3d& x_W) {
  const double u0 = surface.knots_u().domain_begin(), u1 = surface.knots_u().domain_end();
  const double v0 = surface.knots_v().domain_begin(), v1 = surface.knots_v().domain_end();
  constexpr int kGrid = 48;
  Eigen::Vector2d best(u0, v0);
  double best_d = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kGrid; ++i) {
    for (int j = 0; j <= kGrid; ++j) {
      const double u = u0 + (u1 - u0) * i / kGrid, v = v0 + (v1 - v0) * j / kGrid;
      const double d = (pose.Point(surface.Evaluate(u, v, 0).S) - x_W).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = {u, v};
      }
    }
  }
  return best;
}

}  // namespace

Study::Study(RunSpec run)
    : run_(std::move(run)), joints_only_(run_.scene->mechanism), problem_(run_.scene->mechanism) {
  const server::Scene& s = *run_.scene;
  const optimizer::Mechanism& mech = s.mechanism;
  for (const Problem::Entry& e : problem_.equalities()) {  // the unit quaternions
    equality_names_.push_back(
        {"unit quaternion " + mech.body(e.term->body_a()).name, Rhs::kNone, e.row, e.term->dim()});
  }
  for (size_t j = 0; j < s.joints.size(); ++j) {
    const server::JointSpec& js = s.joints[j];
    joints_only_.AddEquality(js.term);
    const int k = problem_.AddEquality(js.term);
    equality_names_.push_back({"joint " + js.name, Rhs::kValue,
                               problem_.equalities()[static_cast<size_t>(k)].row, js.term->dim()});
    if (js.limits) {
      const int l = problem_.AddInequality(js.limits);
      inequality_names_.push_back({"limit " + js.name, Rhs::kAngleBounds,
                                   problem_.inequalities()[static_cast<size_t>(l)].row, 2});
    }
  }
  for (const BoundSpec& b : run_.bounds) {
    const server::JointSpec& js = s.joints[static_cast<size_t>(b.joint)];
    const int l = problem_.AddInequality(optimizer::RevoluteLimits(js.a, js.b, b.lo, b.hi));
    inequality_names_.push_back({"bound " + js.name, Rhs::kAngleBounds,
                                 problem_.inequalities()[static_cast<size_t>(l)].row, 2});
  }
  // Design joints: free within their bounds in the problem, held still in the mechanism whose
  // mobility the dexterity measures.
  for (const DesignJointSpec& d : run_.design_joints) {
    const server::JointSpec& js = s.joints[static_cast<size_t>(d.joint)];
    const int l = problem_.AddInequality(DesignBounds(d));
    inequality_names_.push_back({"design " + js.name,
                                 d.prismatic ? Rhs::kLengthBounds : Rhs::kAngleBounds,
                                 problem_.inequalities()[static_cast<size_t>(l)].row, 2});
    joints_only_.AddEquality(optimizer::JointCoordinate(js.type, js.a, js.b));
  }
  for (const ConstraintSpec& c : run_.constraints) {
    if (c.inequality) {
      const int k = problem_.AddInequality(c.term);
      inequality_names_.push_back({c.name, Rhs::kValue,
                                   problem_.inequalities()[static_cast<size_t>(k)].row,
                                   c.term->dim()});
    } else {
      const int k = problem_.AddEquality(c.term);
      equality_names_.push_back(
          {c.name, Rhs::kValue, problem_.equalities()[static_cast<size_t>(k)].row, c.term->dim()});
    }
  }
  // F = Σ w m is maximized (E = −F) or minimized (E = F). With configurations each measure is
  // the base scene's, on one copy, and F the worst case over the copies.
  sign_ = run_.maximize ? -1.0 : 1.0;
  const ConfigurationsSpec* configurations = run_.configurations.get();
  if (configurations) {
    const server::Scene& base = *configurations->base;
    base_joints_ = std::make_unique<Problem>(base.mechanism);
    for (const server::JointSpec& js : base.joints) base_joints_->AddEquality(js.term);
    for (int j : configurations->design_joints) {
      const server::JointSpec& js = base.joints[static_cast<size_t>(j)];
      base_joints_->AddEquality(optimizer::JointCoordinate(js.type, js.a, js.b));
    }
  }
  const Problem& measured = configurations ? *base_joints_ : joints_only_;
  const server::Scene& measured_scene = configurations ? *configurations->base : s;
  WorstCase::Terms per_copy;
  for (const MeasureSpec& m : run_.terms) {
    if (m.measure == "grasp_distance") {
      auto goal = optimizer::MakePositionGoal(m.end_effector, m.target);
      // A cost (the run file's sign is checked): E gets ½ |w| |P − target|² either way.
      problem_.AddObjective(goal, std::abs(m.weight));
      distance_terms_.push_back(goal);
      dexterity_.push_back(nullptr);
      continue;
    }
    std::vector<std::pair<optimizer::Attachment, optimizer::Attachment>> joints;
    for (int j : m.joints) {
      const server::JointSpec& js = measured_scene.joints[static_cast<size_t>(j)];
      joints.emplace_back(js.a, js.b);
    }
    auto d = std::make_shared<optimizer::Dexterity>(measured, m.end_effector, joints);
    std::shared_ptr<const DesignObjective> f =
        optimizer::MakeDexterityObjective(d, MeasureOf(m.measure));
    const double c = run_.maximize ? m.weight : -m.weight;  // E −= c f
    if (configurations) {
      per_copy.emplace_back(f, m.weight);
    } else if (c > 0.0) {
      problem_.AddDesignObjective(f, c);
    } else {
      problem_.AddDesignObjective(std::make_shared<Negated>(f), -c);
    }
    dexterity_.push_back(d);
    distance_terms_.push_back(nullptr);
  }
  if (configurations) {
    worst_ = std::make_shared<WorstCase>(per_copy, configurations, run_.maximize);
    if (run_.maximize) {
      problem_.AddDesignObjective(worst_, 1.0);
    } else {
      problem_.AddDesignObjective(std::make_shared<Negated>(worst_), 1.0);
    }
  }
  problem_.set_least_astonishment(0.0);
}

optimizer::TermPtr Study::DesignBounds(const DesignJointSpec& d) const {
  const server::JointSpec& js = run_.scene->joints[static_cast<size_t>(d.joint)];
  return d.prismatic ? optimizer::PrismaticLimits(js.a, js.b, d.lo, d.hi)
                     : optimizer::RevoluteLimits(js.a, js.b, d.lo, d.hi);
}

double Study::Objective(const Eigen::VectorXd& q,
                        std::vector<std::pair<std::string, double>>* measures) const {
  if (worst_) {  // each copy's measures, the exact worst case, and F its smooth aggregate
    const ConfigurationsSpec& c = *run_.configurations;
    Eigen::VectorXd F = Eigen::VectorXd::Zero(c.size());
    for (int k = 0; k < c.size(); ++k) {
      const Eigen::VectorXd q_k = c.Gather(k, q);
      for (size_t i = 0; i < run_.terms.size(); ++i) {
        const MeasureSpec& m = run_.terms[i];
        const double value = Measure(dexterity_[i]->Evaluate(q_k, false), m.measure);
        F[k] += m.weight * value;
        if (measures) measures->emplace_back(m.measure + "@" + std::to_string(k + 1), value);
      }
    }
    if (measures) {
      measures->emplace_back("worst case", run_.maximize ? F.minCoeff() : F.maxCoeff());
    }
    return worst_->Aggregate(F);
  }
  std::vector<contact::BodyPose> poses;
  run_.scene->mechanism.Poses(q, &poses);
  double f = 0.0;
  for (size_t k = 0; k < run_.terms.size(); ++k) {
    const MeasureSpec& m = run_.terms[k];
    double value;
    if (dexterity_[k]) {
      value = Measure(dexterity_[k]->Evaluate(q, false), m.measure);
    } else {
      const contact::BodyPose& pose = poses[static_cast<size_t>(m.end_effector.body)];
      value = 0.5 * (pose.Point(m.end_effector.point) - m.target).squaredNorm();
    }
    f += m.weight * value;
    if (measures) measures->emplace_back(m.measure, value);
  }
  return f;
}

std::map<int, double> Study::StartAngles(int index) const {
  const int start = index % run_.num_starts();
  if (start < static_cast<int>(run_.starts.size())) {
    std::map<int, double> angles = run_.starts[static_cast<size_t>(start)].angles;
    AddConfigurations(&angles);
    return angles;
  }
  // Seeded by (seed, start index) alone: the same angles on any thread or rank, and at every
  // grid point.
  const uint64_t k = static_cast<uint64_t>(start);
  std::seed_seq seq{static_cast<uint32_t>(run_.seed), static_cast<uint32_t>(run_.seed >> 32),
                    static_cast<uint32_t>(k), static_cast<uint32_t>(k >> 32)};
  std::mt19937_64 gen(seq);
  std::map<int, double> angles;
  for (int j : run_.random_joints) {
    double lo = -std::numbers::pi, hi = std::numbers::pi;
    for (const BoundSpec& b : run_.bounds) {
      if (b.joint == j) lo = b.lo, hi = b.hi;
    }
    for (const DesignJointSpec& d : run_.design_joints) {
      if (d.joint == j) lo = d.lo, hi = d.hi;
    }
    // (uniform_real_distribution's algorithm is the library's: fixed for one build.)
    const double t = static_cast<double>(gen() >> 11) * 0x1.0p-53;
    angles[j] = lo + (hi - lo) * t;
  }
  AddConfigurations(&angles);
  return angles;
}

void Study::AddConfigurations(std::map<int, double>* angles) const {
  if (!run_.configurations) return;
  const ConfigurationsSpec& c = *run_.configurations;
  for (int k = 0; k < c.size(); ++k) {
    (*angles)[c.Joint(k, c.joint)] = c.values[static_cast<size_t>(k)];
  }
}

void Study::AddMechanism(Problem* p, bool bounded) const {
  const server::Scene& s = *run_.scene;
  for (const server::JointSpec& js : s.joints) {
    p->AddEquality(js.term);
    if (bounded && js.limits) p->AddInequality(js.limits);
  }
  if (!bounded) return;
  for (const BoundSpec& b : run_.bounds) {
    const server::JointSpec& js = s.joints[static_cast<size_t>(b.joint)];
    p->AddInequality(optimizer::RevoluteLimits(js.a, js.b, b.lo, b.hi));
  }
  for (const DesignJointSpec& d : run_.design_joints) p->AddInequality(DesignBounds(d));
}

optimizer::SolveStats Study::Settle(const Problem& p, int index, int rounds,
                                    Eigen::VectorXd* q) const {
  optimizer::SolverOptions o;
  o.max_iterations = 200;
  o.kkt_tolerance = 1e-12;
  optimizer::Solver solver(p, o);
  PrepareData(index, *q, &solver.data());
  optimizer::SolveStats st;
  for (int round = 0; round < rounds; ++round) {
    st = solver.Solve(q);
    if (st.converged && st.iterations <= 1) break;
  }
  return st;
}

Eigen::VectorXd Study::Assemble(int index, const std::map<int, double>& angles, bool* ok,
                                bool* feasible) const {
  // The joints at the start angles: minimize Σ (θ_j − target_j)² subject to the scene's joints,
  // from the scene's initial pose (repeated warm solves: each is anchored at its start). Then,
  // from there, the same with the run's constraints and bounds too, so that the design solve
  // starts feasible (a cold start far from its constraints drives the multipliers up before
  // the objective is seen). When that fails (an infeasible set) the joints-only start is kept:
  // the design solve then reports the conflict.
  const server::Scene& s = *run_.scene;
  auto solve = [&](bool constrained, Eigen::VectorXd* q) {
    Problem p(s.mechanism);
    AddMechanism(&p, constrained);
    if (constrained) {
      for (const ConstraintSpec& c : run_.constraints) {
        if (c.inequality) {
          p.AddInequality(c.term);
        } else {
          p.AddEquality(c.term);
        }
      }
    }
    for (const auto& [j, theta] : angles) {
      const server::JointSpec& js = s.joints[static_cast<size_t>(j)];
      // (x − lo)² + (hi − x)² is least at the middle of [lo, hi]: a goal on the coordinate.
      p.AddObjective(js.type == "prismatic"
                         ? optimizer::PrismaticLimits(js.a, js.b, theta - 1e-4, theta + 1e-4)
                         : optimizer::RevoluteLimits(js.a, js.b, theta - 1e-3, theta + 1e-3),
                     1.0);
    }
    p.set_least_astonishment(1e-9);
    // (Fewer rounds with the run's constraints: a set that cannot be met is diagnosed by
    // ReportInfeasible, not by trying longer.)
    const optimizer::SolveStats st = Settle(p, index, constrained ? 4 : 20, q);
    return st.max_violation <= 1e-9 && q->allFinite();
  };
  Eigen::VectorXd q = s.mechanism.InitialCoordinates();
  *ok = solve(false, &q);
  if (feasible) *feasible = false;
  if (!*ok) return q;
  Eigen::VectorXd constrained = q;
  if (solve(true, &constrained)) {
    q = constrained;
    if (feasible) *feasible = true;
  }
  return q;
}

std::vector<std::pair<std::string, double>> Study::GridPoint(int index) const {
  std::vector<std::pair<std::string, double>> point;
  int g = index / run_.num_starts();
  std::vector<int> at(run_.grid.size());
  for (size_t a = run_.grid.size(); a-- > 0;) {  // the last axis fastest
    const int m = static_cast<int>(run_.grid[a].values.size());
    at[a] = g % m;
    g /= m;
  }
  for (size_t a = 0; a < run_.grid.size(); ++a) {
    const GridAxis& axis = run_.grid[a];
    point.emplace_back(run_.constraints[static_cast<size_t>(axis.constraint)].name + " row " +
                           std::to_string(axis.row),
                       axis.values[static_cast<size_t>(at[a])]);
  }
  return point;
}

void Study::PrepareData(int index, const Eigen::VectorXd& q, optimizer::ProblemData* data) const {
  // The case's right-hand sides: the run file's, with the grid point's rows.
  std::vector<Eigen::VectorXd> rhs;
  for (const ConstraintSpec& c : run_.constraints) rhs.push_back(c.rhs);
  if (index >= 0) {
    const auto point = GridPoint(index);
    for (size_t a = 0; a < run_.grid.size(); ++a) {
      rhs[static_cast<size_t>(run_.grid[a].constraint)][run_.grid[a].row] = point[a].second;
    }
  }
  // Point-on-surface constraints track the closest point: seed each at this configuration's.
  const server::Scene& s = *run_.scene;
  std::vector<contact::BodyPose> poses;
  s.mechanism.Poses(q, &poses);
  for (size_t k = 0; k < run_.constraints.size(); ++k) {
    const ConstraintSpec& c = run_.constraints[k];
    if (!data->HasState(*c.term)) continue;
    auto& st = data->StateAs<optimizer::ShiftedState>(*c.term);
    st.rhs = rhs[k];
    if (c.surface < 0) continue;
    const auto& term = dynamic_cast<const optimizer::PointOnSurfaceTerm&>(*c.inner);
    const server::SceneSurface& ss = s.surfaces[static_cast<size_t>(c.surface)];
    auto& inner = dynamic_cast<optimizer::PointOnSurfaceTerm::State&>(*st.inner);
    inner.u = NearestSample(ss.surface, poses[static_cast<size_t>(ss.body)],
                            poses[static_cast<size_t>(term.body_a())].Point(term.point().point));
    inner.valid = false;
  }
}

Eigen::VectorXd Study::StartConfiguration(int index, bool* ok) const {
  return Assemble(index, StartAngles(index), ok, nullptr);
}

CaseResult Study::Solve(int index) const {
  using Clock = std::chrono::steady_clock;
  const server::Scene& s = *run_.scene;
  CaseResult r;
  r.index = index;
  const std::map<int, double> angles = StartAngles(index);
  for (const auto& [j, theta] : angles) {
    const bool prismatic = s.joints[static_cast<size_t>(j)].type == "prismatic";
    r.start_deg.emplace_back(s.joints[static_cast<size_t>(j)].name + (prismatic ? " (m)" : ""),
                             prismatic ? theta : theta / kDeg);
  }
  const auto t0 = Clock::now();
  bool assembled = false;
  r.grid = GridPoint(index);
  bool feasible = false;
  Eigen::VectorXd q = Assemble(index, angles, &assembled, &feasible);
  r.q = q;
  if (!assembled) {
    r.status = "start failed: the scene's joints could not be assembled at these angles";
    return r;
  }
  // The run's constraints could not be met from this start: when the least-violation point
  // confirms it, that is the result (a grid's unreachable points cost one such solve each).
  if (!feasible && ReportInfeasible(index, &r)) {
    r.time_ms = 1e3 * std::chrono::duration<double>(Clock::now() - t0).count();
    return r;
  }
  optimizer::SolverOptions o;
  o.design.enabled = true;
  o.design.relative_kkt_tolerance = run_.relative_kkt_tolerance;
  o.max_iterations = run_.max_iterations;
  o.constraint_tolerance = run_.constraint_tolerance;
  optimizer::Solver solver(problem_, o);
  PrepareData(index, q, &solver.data());
  std::vector<contact::BodyPose> poses;
  solver.set_history(&r.history);
  const optimizer::SolveStats st = solver.Solve(&q);
  r.time_ms = 1e3 * std::chrono::duration<double>(Clock::now() - t0).count();
  for (optimizer::IterationRecord& h : r.history) h.objective *= sign_;
  r.q = q;
  r.converged = st.converged;
  r.violation = st.max_violation;
  r.kkt = st.kkt_residual;
  r.iterations = st.iterations;
  r.objective = Objective(q, &r.measures);
  s.mechanism.Poses(q, &poses);
  for (const server::JointSpec& js : s.joints) {
    if (js.type == "revolute") {
      r.joints_deg.emplace_back(js.name, optimizer::RevoluteAngle(js.a, js.b, poses) / kDeg);
    }
  }
  for (const DesignJointSpec& d : run_.design_joints) {
    const server::JointSpec& js = s.joints[static_cast<size_t>(d.joint)];
    r.design.emplace_back(js.name + (d.prismatic ? " (m)" : " (deg)"),
                          d.prismatic ? optimizer::PrismaticDisplacement(js.a, js.b, poses)
                                      : optimizer::RevoluteAngle(js.a, js.b, poses) / kDeg);
  }
  for (const ConstraintSpec& c : run_.constraints) {
    if (c.surface < 0) continue;
    const auto& shifted = solver.data().StateAs<optimizer::ShiftedState>(*c.term);
    r.contacts.emplace_back(
        c.name, dynamic_cast<const optimizer::PointOnSurfaceTerm::State&>(*shifted.inner).u);
  }
  // Sensitivities: ∇E = Jᵀλ, so dE*/db = λ for r(q) = b (or ≥ b), and F = sign_ · E.
  const Eigen::VectorXd& le = solver.equality_multipliers();
  const Eigen::VectorXd& li = solver.inequality_multipliers();
  for (const RowName& n : equality_names_) {
    if (n.rhs == Rhs::kNone) continue;
    for (int k = 0; k < n.dim; ++k) {
      const double l = le[n.first_row + k];
      r.sensitivities.push_back({n.constraint, k, "rhs", l, sign_ * l, true});
    }
  }
  for (const RowName& n : inequality_names_) {
    for (int k = 0; k < n.dim; ++k) {
      const double l = li[n.first_row + k];
      if (n.rhs == Rhs::kValue) {
        r.sensitivities.push_back({n.constraint, k, "rhs", l, sign_ * l, l > 0.0});
      } else if (n.rhs == Rhs::kLengthBounds) {  // d − lo ≥ 0, hi − d ≥ 0; per metre
        r.sensitivities.push_back({n.constraint, k, k == 0 ? "min" : "max", l,
                                   (k == 0 ? 1.0 : -1.0) * sign_ * l, l > 0.0});
      } else {  // θ − lo ≥ 0 (row 0), hi − θ ≥ 0 (row 1); per degree
        r.sensitivities.push_back({n.constraint, k, k == 0 ? "min_deg" : "max_deg", l,
                                   (k == 0 ? 1.0 : -1.0) * sign_ * l * kDeg, l > 0.0});
      }
    }
  }
  // Status: an optimum, or why not (an infeasible set names its violated rows).
  optimizer::ProblemEvaluator ev(problem_, false);
  ev.Evaluate(q);
  // Violated rows, worst first (at a least-violation point the conflict is spread over the rows
  // involved; the constraint that cannot be met leads).
  std::vector<std::pair<double, std::string>> violated;
  auto check = [&](const std::vector<RowName>& names, const Eigen::VectorXd& c, bool ineq) {
    for (const RowName& n : names) {
      for (int k = 0; k < n.dim; ++k) {
        const double v = c[n.first_row + k];
        const double bad = ineq ? -v : std::abs(v);
        if (bad > 1e3 * run_.constraint_tolerance) {
          violated.emplace_back(bad, n.constraint + " row " + std::to_string(k) + ": " +
                                         (ineq ? "below zero by " : "off by ") +
                                         nlohmann::json(bad).dump());
        }
      }
    }
  };
  check(equality_names_, ev.c_e(), false);
  check(inequality_names_, ev.c_i(), true);
  std::stable_sort(violated.begin(), violated.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [size, text] : violated) r.violated.push_back(text);
  if (st.converged) {
    r.status = "optimum";
  } else if (!r.violated.empty()) {
    if (!ReportInfeasible(index, &r)) r.status = "infeasible";
  } else {
    r.status = "not converged";
  }
  return r;
}

bool Study::ReportInfeasible(int index, CaseResult* r) const {
  // The least-violation point with the mechanism intact: the scene's joints, limits and the
  // run's bounds and inequalities hard, the run's equalities as least squares ½ Σ |r − rhs|².
  // Those left unmet there are what cannot be had together with the mechanism.
  Problem p(run_.scene->mechanism);
  AddMechanism(&p, true);
  std::vector<int> soft;
  for (size_t k = 0; k < run_.constraints.size(); ++k) {
    const ConstraintSpec& c = run_.constraints[k];
    if (c.inequality) {
      p.AddInequality(c.term);
    } else {
      p.AddObjective(c.term, 1.0);
      soft.push_back(static_cast<int>(k));
    }
  }
  p.set_least_astonishment(1e-9);
  bool assembled = false;
  const Eigen::VectorXd start = Assemble(index, {}, &assembled, nullptr);
  // (From the scene's pose: the diverged iterate may be far off.)
  Eigen::VectorXd q = assembled ? start : r->q;
  const optimizer::SolveStats st = Settle(p, index, 20, &q);
  if (!(st.max_violation <= 1e-9)) return false;  // the hard set itself conflicts
  optimizer::ProblemEvaluator ev(p, false);
  ev.Evaluate(q);
  std::vector<std::string> unmet;
  double worst = 0.0;
  for (size_t k = 0; k < soft.size(); ++k) {
    const ConstraintSpec& c = run_.constraints[static_cast<size_t>(soft[k])];
    const double off = ev.r_o().segment(p.objectives()[k].row, c.term->dim()).cwiseAbs().maxCoeff();
    if (off > 1e3 * run_.constraint_tolerance) {
      unmet.push_back(c.name + ": off by " + nlohmann::json(off).dump() +
                      " at the least-violation point with the mechanism intact");
      worst = std::max(worst, off);
    }
  }
  if (unmet.empty()) return false;
  r->status = "infeasible";
  r->violated = unmet;
  r->q = q;
  r->violation = worst;
  r->measures.clear();
  r->objective = Objective(q, &r->measures);
  r->converged = false;
  return true;
}

nlohmann::json Study::ToJson(const CaseResult& c) const {
  nlohmann::json j;
  j["case"] = c.index;
  j["status"] = c.status;
  nlohmann::json start = nlohmann::json::object();
  for (const auto& [name, deg] : c.start_deg) start[name] = deg;
  j["start_deg"] = start;
  j["start"] = c.index % run_.num_starts();
  nlohmann::json grid = nlohmann::json::object();
  for (const auto& [name, value] : c.grid) grid[name] = value;
  j["grid"] = grid;
  j["converged"] = c.converged;
  j["objective"] = c.objective;
  nlohmann::json measures = nlohmann::json::array();
  for (const auto& [name, value] : c.measures) measures.push_back({{name, value}});
  j["measures"] = measures;
  j["violation"] = c.violation;
  j["kkt"] = c.kkt;
  j["iterations"] = c.iterations;
  j["time_ms"] = c.time_ms;
  nlohmann::json joints = nlohmann::json::object();
  for (const auto& [name, deg] : c.joints_deg) joints[name] = deg;
  j["joints_deg"] = joints;
  nlohmann::json design = nlohmann::json::object();
  for (const auto& [name, value] : c.design) design[name] = value;
  j["design"] = design;
  nlohmann::json contacts = nlohmann::json::object();
  for (const auto& [name, u] : c.contacts) contacts[name] = {u[0], u[1]};
  j["contacts_uv"] = contacts;
  j["q"] = std::vector<double>(c.q.data(), c.q.data() + c.q.size());
  nlohmann::json sens = nlohmann::json::array();
  for (const Sensitivity& s : c.sensitivities) {
    sens.push_back({{"constraint", s.constraint},
                    {"row", s.row},
                    {"wrt", s.wrt},
                    {"multiplier", s.multiplier},
                    {"d_objective", s.derivative},
                    {"active", s.active}});
  }
  j["sensitivities"] = sens;
  nlohmann::json history = nlohmann::json::array();
  for (const optimizer::IterationRecord& h : c.history) {
    history.push_back({h.iteration, h.objective, h.violation, h.kkt});
  }
  j["history"] = {{"columns", {"iteration", "objective", "violation", "kkt"}}, {"rows", history}};
  j["violated"] = c.violated;
  return j;
}

nlohmann::json Study::Geometry(const Eigen::VectorXd& q) const {
  // What a plot of the mechanism needs, in the world frame (m): each body as the points its
  // joints and end effectors attach at, each scene surface sampled on a 25 x 25 grid, and each
  // dexterity term's end effector with its Jacobian J (3 x m).
  const server::Scene& s = *run_.scene;
  std::vector<contact::BodyPose> poses;
  s.mechanism.Poses(q, &poses);
  std::vector<std::vector<Eigen::Vector3d>> points(static_cast<size_t>(s.mechanism.num_bodies()));
  auto add = [&](const optimizer::Attachment& a) {
    points[static_cast<size_t>(a.body)].push_back(
        poses[static_cast<size_t>(a.body)].Point(a.point));
  };
  for (const server::JointSpec& js : s.joints) {
    add(js.a);
    add(js.b);
  }
  // Each term's end effector (on every copy, with configurations) and the coordinates its
  // measure is taken at.
  struct Effector {
    size_t term;
    optimizer::Attachment at;
    Eigen::VectorXd q;
  };
  std::vector<Effector> effectors_at;
  for (size_t k = 0; k < run_.terms.size(); ++k) {
    const optimizer::Attachment& ee = run_.terms[k].end_effector;
    if (!run_.configurations) {
      effectors_at.push_back({k, ee, q});
      continue;
    }
    const ConfigurationsSpec& c = *run_.configurations;
    for (int copy = 0; copy < c.size(); ++copy) {
      optimizer::Attachment at = ee;
      at.body = c.Body(copy, ee.body);
      effectors_at.push_back({k, at, c.Gather(copy, q)});
    }
  }
  for (const Effector& e : effectors_at) add(e.at);
  nlohmann::json bodies = nlohmann::json::array();
  for (int b = 0; b < s.mechanism.num_bodies(); ++b) {
    nlohmann::json pts = nlohmann::json::array();
    for (const Eigen::Vector3d& x : points[static_cast<size_t>(b)])
      pts.push_back({x[0], x[1], x[2]});
    bodies.push_back({{"name", s.mechanism.body(b).name},
                      {"fixed", s.mechanism.body(b).fixed},
                      {"points", pts}});
  }
  nlohmann::json surfaces = nlohmann::json::array();
  for (const server::SceneSurface& ss : s.surfaces) {
    const nurbs::NurbsSurface& f = ss.surface;
    constexpr int kN = 25;
    nlohmann::json x = nlohmann::json::array(), y = x, z = x;
    for (int i = 0; i < kN; ++i) {
      nlohmann::json rx = nlohmann::json::array(), ry = rx, rz = rx;
      for (int j = 0; j < kN; ++j) {
        const double u = f.knots_u().domain_begin() +
                         (f.knots_u().domain_end() - f.knots_u().domain_begin()) * i / (kN - 1);
        const double v = f.knots_v().domain_begin() +
                         (f.knots_v().domain_end() - f.knots_v().domain_begin()) * j / (kN - 1);
        const Eigen::Vector3d p = poses[static_cast<size_t>(ss.body)].Point(f.Evaluate(u, v, 0).S);
        rx.push_back(p[0]);
        ry.push_back(p[1]);
        rz.push_back(p[2]);
      }
      x.push_back(rx);
      y.push_back(ry);
      z.push_back(rz);
    }
    surfaces.push_back({{"name", ss.name}, {"x", x}, {"y", y}, {"z", z}});
  }
  nlohmann::json effectors = nlohmann::json::array();
  for (const Effector& ea : effectors_at) {
    const size_t k = ea.term;
    const MeasureSpec& m = run_.terms[k];
    const Eigen::Vector3d p = poses[static_cast<size_t>(ea.at.body)].Point(ea.at.point);
    nlohmann::json e = {{"measure", m.measure}, {"point", {p[0], p[1], p[2]}}};
    if (dexterity_[k]) {
      try {
        const Eigen::MatrixXd J = dexterity_[k]->Evaluate(ea.q, false).J;
        nlohmann::json rows = nlohmann::json::array();
        for (int r = 0; r < 3; ++r) {
          rows.push_back(std::vector<double>(J.cols()));
          for (int c = 0; c < J.cols(); ++c)
            rows[static_cast<size_t>(r)][static_cast<size_t>(c)] = J(r, c);
        }
        e["jacobian"] = rows;
      } catch (const std::runtime_error&) {  // (singular here: no ellipsoid)
      }
    }
    effectors.push_back(e);
  }
  return {{"bodies", bodies}, {"surfaces", surfaces}, {"end_effectors", effectors}};
}

nlohmann::json Study::Header() const {
  const server::Scene& s = *run_.scene;
  nlohmann::json j;
  j["run"] = run_.path;
  j["scene"] = run_.scene_path;
  j["sense"] = run_.maximize ? "maximize" : "minimize";
  nlohmann::json terms = nlohmann::json::array();
  for (const MeasureSpec& m : run_.terms) {
    nlohmann::json t = {{"measure", m.measure}, {"weight", m.weight}};
    std::vector<std::string> joints;
    const server::Scene& named = run_.configurations ? *run_.configurations->base : s;
    for (int k : m.joints) joints.push_back(named.joints[static_cast<size_t>(k)].name);
    if (!joints.empty()) t["joints"] = joints;
    terms.push_back(t);
  }
  j["objective"] = terms;
  if (run_.configurations) {
    const ConfigurationsSpec& c = *run_.configurations;
    const server::JointSpec& js = c.base->joints[static_cast<size_t>(c.joint)];
    std::vector<double> values;
    for (double v : c.values) values.push_back(c.prismatic ? v : v / kDeg);
    j["configurations"] = {{"joint", js.name},
                           {c.prismatic ? "values" : "values_deg", values},
                           {"tolerance", c.tolerance},
                           {"objective",
                            "worst case over the configurations, smoothed: within "
                            "tolerance of the exact worst case (measures \"worst "
                            "case\")"}};
  }
  std::vector<std::string> constraints;
  for (const ConstraintSpec& c : run_.constraints) constraints.push_back(c.name);
  j["constraints"] = constraints;
  j["variables"] = "configuration: " + std::to_string(s.mechanism.num_moving()) +
                   " moving bodies x 7 maximal coordinates";
  j["cases"] = num_cases();
  j["starts"] = run_.num_starts();
  nlohmann::json grid = nlohmann::json::array();
  for (const GridAxis& a : run_.grid) {
    grid.push_back({{"name", run_.constraints[static_cast<size_t>(a.constraint)].name + " row " +
                                 std::to_string(a.row)},
                    {"values", a.values}});
  }
  j["grid"] = grid;
  j["seed"] = run_.seed;
  return j;
}

}  // namespace tangent::design
