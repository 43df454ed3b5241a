#pragma once

// Run files of tangent-opt (docs/offline.md "Run files"): a scene, the objective, extra
// constraints, bounds on joint angles, and the starts. Errors name the file, the JSON pointer
// of the item and the problem: "runs/x.json: /bounds/1/joint: no joint named \"elbw\"".

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "design/configurations.h"
#include "optimizer/joints.h"
#include "optimizer/term.h"
#include "server/scene.h"

namespace tangent::design {

class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One term of the objective F = Σ weight · measure (maximized or minimized as a whole).
struct MeasureSpec {
  /// dexterity √det(JJᵀ), inverse_condition σ_min/σ_max, force_transmission 1/σ_max (of the
  /// end effector with respect to the chosen revolute joints), or grasp_distance ½|P − target|².
  std::string measure;
  double weight = 1.0;
  optimizer::Attachment end_effector;
  std::vector<int> joints;                           ///< scene joint indices (revolute)
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< grasp_distance, world, m
};

/// An extra constraint of the run: its name (for sensitivities), whether it is an inequality
/// (r ≥ 0) or an equality (r = 0), and its term.
struct ConstraintSpec {
  std::string name;
  std::string type;
  bool inequality = false;
  optimizer::TermPtr term;   ///< r(q) − rhs, the term the problem holds
  optimizer::TermPtr inner;  ///< r(q) itself
  Eigen::VectorXd rhs;       ///< the file's "rhs" (default 0): r(q) = rhs, or ≥ rhs
  /// point_on_surface / point_above_surface: the surface (scene index), to seed the tracking.
  int surface = -1;
};

/// A design parameter: a scene joint (prismatic: a length; revolute: an angle) whose coordinate
/// the study chooses within [lo, hi] (m or rad) — a link's length as a slider in the link, an
/// attachment point or a surface's placement on a sub-body. It is held still where the
/// mechanism's mobility is defined (the dexterity's), so it is a design, not a motion.
struct DesignJointSpec {
  int joint = 0;
  bool prismatic = true;
  double lo = 0.0, hi = 0.0;
};

/// Bounds on a revolute joint's angle (radians inside; degrees in the file).
struct BoundSpec {
  int joint = 0;
  double lo = 0.0, hi = 0.0;
};

/// A start: joint coordinates (revolute: radians; prismatic: metres) the configuration is
/// assembled to before the design solve; joints not named keep the scene's initial pose as far
/// as the closure allows.
struct StartSpec {
  std::map<int, double> angles;
};

/// A sweep axis: the values one row of a constraint's right-hand side takes (in metres or
/// radians as the constraint's rows are); the cases are the grid's points times the starts.
struct GridAxis {
  int constraint = 0;  ///< index into RunSpec::constraints
  int row = 0;
  std::vector<double> values;
};

struct RunSpec {
  std::string path;  ///< the run file
  std::string scene_path;
  std::unique_ptr<server::Scene> scene;
  bool maximize = true;
  std::vector<MeasureSpec> terms;
  std::vector<ConstraintSpec> constraints;
  std::vector<BoundSpec> bounds;
  std::vector<DesignJointSpec> design_joints;
  std::vector<StartSpec> starts;
  /// N seeded random starts: coordinates of `random_joints` drawn uniformly within their
  /// bounds (or (−π, π] when unbounded; design joints within theirs) by a generator seeded with
  /// (seed, start index).
  int random_starts = 0;
  uint64_t seed = 1;
  std::vector<int> random_joints;
  std::vector<GridAxis> grid;  ///< empty: one point (the constraints' own rhs)
  /// Design over a range of motion (configurations.h), or null. When set, `scene` is the
  /// replica (K copies of the moving bodies) and every joint index above is the replica's,
  /// except the measures' (`terms`: end effector and joints index the base scene, the measure
  /// being taken on each copy); the configurations' equalities are the first constraints.
  std::unique_ptr<ConfigurationsSpec> configurations;
  int max_iterations = 500;
  double relative_kkt_tolerance = 1e-9;
  double constraint_tolerance = 1e-12;

  /// The starts in order: the listed ones, then the random ones.
  int num_starts() const { return static_cast<int>(starts.size()) + random_starts; }
  int num_grid_points() const {
    int n = 1;
    for (const GridAxis& a : grid) n *= static_cast<int>(a.values.size());
    return n;
  }
  /// Case k is start k % num_starts() at grid point k / num_starts() (the first axis slowest).
  int num_cases() const { return num_starts() * num_grid_points(); }
};

/// Parses a run file's text; `where` names it in errors, `base_dir` resolves the scene path.
/// @throws RunError (a bad scene file too, its message kept).
RunSpec ParseRun(const std::string& text, const std::string& where, const std::string& base_dir);
/// Loads a run file. @throws RunError.
RunSpec LoadRun(const std::string& path);

}  // namespace tangent::design
