#pragma once

// A design study (tangent-opt): the run's problem built once from the scene and the run file
// and shared read-only by every case; each case (a start) assembles its start configuration and
// is solved to convergence by the solver's design mode on its own data, so cases run on any
// number of threads or MPI ranks with bit-identical results.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "design/configurations.h"
#include "design/run_file.h"
#include "optimizer/dexterity.h"
#include "optimizer/problem.h"
#include "optimizer/solver.h"

namespace tangent::design {

/// d F*/d b for one constraint row or bound, F the run's objective.
struct Sensitivity {
  std::string constraint;   ///< "tip on plane", "joint elbow", "bound elbow min" ...
  int row = 0;              ///< the row within the constraint
  std::string wrt;          ///< what b is: "rhs" (r(q) = b, or ≥ b), "min_deg", "max_deg"
  double multiplier = 0.0;  ///< the solver's λ for the row (∇E = Jᵀλ)
  double derivative = 0.0;  ///< d F*/d b (per metre or radian of rhs, per degree of a bound)
  bool active = true;       ///< inequalities: λ > 0
};

struct CaseResult {
  int index = 0;
  std::vector<std::pair<std::string, double>> start_deg;  ///< the start's joint angles
  std::vector<std::pair<std::string, double>> grid;       ///< the grid point's rhs rows
  std::string status;  ///< "optimum", "not converged", "infeasible", "start failed: ..."
  bool converged = false;
  double objective = 0.0;                                ///< F at the result
  std::vector<std::pair<std::string, double>> measures;  ///< each objective term's measure
  double violation = 0.0, kkt = 0.0;
  int iterations = 0;
  double time_ms = 0.0;
  std::vector<optimizer::IterationRecord> history;  ///< objective as F
  Eigen::VectorXd q;
  std::vector<std::pair<std::string, double>> joints_deg;  ///< every revolute joint's angle
  std::vector<std::pair<std::string, double>> design;      ///< design joints' values (m, deg)
  /// Point-on-surface constraints: the contact's (u, v) on its surface.
  std::vector<std::pair<std::string, Eigen::Vector2d>> contacts;
  std::vector<Sensitivity> sensitivities;
  std::vector<std::string> violated;  ///< rows above the tolerance (infeasible results)
};

class Study {
 public:
  /// @throws RunError when the problem cannot be built (e.g. a dexterity measure whose joints
  /// do not parameterize the mechanism).
  explicit Study(RunSpec run);
  Study(const Study&) = delete;
  Study& operator=(const Study&) = delete;

  const RunSpec& run() const { return run_; }
  const optimizer::Problem& problem() const { return problem_; }
  int num_cases() const { return run_.num_cases(); }
  /// Solves case `index` (thread safe: reads the shared problem, owns its data).
  CaseResult Solve(int index) const;
  /// The objective F at q and each term's measure.
  double Objective(const Eigen::VectorXd& q,
                   std::vector<std::pair<std::string, double>>* measures = nullptr) const;
  /// The start angles of case `index` (listed, or drawn from the seeded generator).
  std::map<int, double> StartAngles(int index) const;
  /// The configuration case `index` starts from: the scene's joints assembled at its angles
  /// (*ok false when they cannot be).
  Eigen::VectorXd StartConfiguration(int index, bool* ok) const;
  /// Makes `data` (of the study's problem, or of any problem holding its constraint terms) ready
  /// for case `index` from q: the constraints' right-hand sides at the case's grid point (index
  /// < 0: the run file's), and the tracked closest points of point-on-surface constraints seeded
  /// at q.
  void PrepareData(int index, const Eigen::VectorXd& q, optimizer::ProblemData* data) const;
  /// The grid point of case `index`: each axis's name and value.
  std::vector<std::pair<std::string, double>> GridPoint(int index) const;

  nlohmann::json ToJson(const CaseResult& c) const;
  /// The result file's header: run, scene, objective and variables.
  nlohmann::json Header() const;
  /// The mechanism at q for plots: bodies as attachment points, surfaces sampled, end effectors
  /// with their Jacobians (world frame, m).
  nlohmann::json Geometry(const Eigen::VectorXd& q) const;

 private:
  /// What a row's multiplier is the sensitivity to: nothing reported (unit quaternions), the
  /// right-hand side b of r(q) = b or ≥ b, or a two-row bound [lo, hi] on an angle (per
  /// degree) or a length (per metre).
  enum class Rhs { kNone, kValue, kAngleBounds, kLengthBounds };
  struct RowName {
    std::string constraint;
    Rhs rhs = Rhs::kValue;
    int first_row = 0, dim = 0;
  };
  /// The start of case `index`: the scene's joints at `angles` (*ok), then the run's
  /// constraints and bounds met too where they can be (*feasible, may be null).
  optimizer::TermPtr DesignBounds(const DesignJointSpec& d) const;
  /// With configurations: each copy's configuration joint at its value.
  void AddConfigurations(std::map<int, double>* angles) const;
  /// Adds the scene's joints to p and, with `bounded`, their limits, the run's bounds and the
  /// design joints' bounds.
  void AddMechanism(optimizer::Problem* p, bool bounded) const;
  /// Solves p from *q by repeated warm solves (each anchored at its start) until one takes at
  /// most an iteration, for at most `rounds`; the run's constraints in p get case `index`'s
  /// right-hand sides and seeds. @return the last solve's stats.
  optimizer::SolveStats Settle(const optimizer::Problem& p, int index, int rounds,
                               Eigen::VectorXd* q) const;
  Eigen::VectorXd Assemble(int index, const std::map<int, double>& angles, bool* ok,
                           bool* feasible) const;
  /// Finds the least-violation point with the mechanism intact; when the run's equality
  /// constraints are unmet there, makes *r that infeasible result (naming them) and returns
  /// true.
  bool ReportInfeasible(int index, CaseResult* r) const;

  RunSpec run_;
  optimizer::Problem joints_only_;  ///< the scene's joints: the dexterity's mechanism
  optimizer::Problem problem_;
  /// With configurations: the base scene's joints (the measures' mechanism, one copy) and the
  /// worst case over the copies, the objective.
  std::unique_ptr<optimizer::Problem> base_joints_;
  std::shared_ptr<WorstCase> worst_;
  std::vector<std::shared_ptr<optimizer::Dexterity>> dexterity_;  ///< per term (or null)
  std::vector<optimizer::TermPtr> distance_terms_;                ///< per term (or null)
  std::vector<RowName> equality_names_, inequality_names_;
  double sign_ = -1.0;  ///< F = sign_ · E
};

}  // namespace tangent::design
