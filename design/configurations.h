#pragma once

// Design over a range of motion (docs/offline.md "Over a range of motion"): a four-bar's link
// length for the best worst-case force transmission over its crank's working range. One design
// must serve every configuration, so the study solves the mechanism at K configurations at once:
//   - the bodies joined to the ground through design and fixed joints only (the design side: an
//     adjustable pivot's slider, say) are shared, one pose for all configurations;
//   - every other moving body has K copies ("crank@1" … "crank@K"), each copy's joints joining
//     its own bodies, and copy k's configuration joint held at its value θ_k by an equality
//     whose multiplier is the sensitivity dF*/dθ_k;
//   - the objective is the worst case over the copies of F_k = Σ_i w_i m_i(q_k), the run's
//     measures of copy k, made smooth by Kreisselmeier–Steinhauser aggregation:
//         maximize:  KS(q) = −(1/ρ) log((1/K) Σ_k exp(−ρ F_k)),   min F_k ≤ KS ≤ min F_k + δ
//         minimize:  KS(q) =  (1/ρ) log((1/K) Σ_k exp( ρ F_k)),   max F_k − δ ≤ KS ≤ max F_k
//     with ρ = log(K)/δ, δ the run file's tolerance in the measure's units; its gradient is
//     Σ_k π_k ∇F_k with π_k = exp(∓ρ F_k)/Σ exp(∓ρ F_j), the copies' weights.
// Each measure is the base scene's own (its Dexterity over one copy of the mechanism),
// evaluated at copy k's coordinates gathered from the replica's q; shared bodies collect the
// gradients of every copy.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "optimizer/problem.h"
#include "server/scene.h"

namespace tangent::design {

/// The configurations of a run and the replica scene's index maps.
struct ConfigurationsSpec {
  int joint = -1;                       ///< the base scene's configuration joint
  bool prismatic = false;               ///< values in m (else rad)
  std::vector<double> values;           ///< θ_k (rad) or d_k (m), k = 0 … K−1
  double tolerance = 0.0;               ///< δ, the aggregate's gap to the exact worst case
  std::unique_ptr<server::Scene> base;  ///< the scene as written
  std::vector<int> design_joints;       ///< the run's design joints, base indices
  /// [k][base body or joint] → the replica's; shared bodies and joints map to one index.
  std::vector<std::vector<int>> bodies, joints;
  /// [k][base coordinate] → the replica's coordinate.
  std::vector<std::vector<int>> gather;
  std::vector<bool> shared_body;  ///< per base body: on the design side (one copy)

  int size() const { return static_cast<int>(values.size()); }
  /// Copy k's replica of base body b / base joint j.
  int Body(int k, int b) const { return bodies[static_cast<size_t>(k)][static_cast<size_t>(b)]; }
  int Joint(int k, int j) const { return joints[static_cast<size_t>(k)][static_cast<size_t>(j)]; }
  /// Copy k's coordinates (base layout) from the replica's q.
  Eigen::VectorXd Gather(int k, const Eigen::VectorXd& q) const;
  /// g += the base-layout gradient g_k of copy k, scattered to the replica's layout.
  void ScatterAdd(int k, const Eigen::VectorXd& g_k, Eigen::VectorXd* g) const;
};

/// Builds the replica of c->base: fills c's maps and returns the scene the study solves.
/// @throws std::invalid_argument naming the joint when a design joint would move with the
/// configurations (it must join design-side bodies) or the configuration joint joins two
/// design-side bodies.
std::unique_ptr<server::Scene> Replicate(ConfigurationsSpec* c);

/// The worst case over the configurations of F_k = Σ_i w_i f_i(q_k) (KS-smoothed, see above).
class WorstCase final : public optimizer::DesignObjective {
 public:
  using Terms = std::vector<std::pair<std::shared_ptr<const optimizer::DesignObjective>, double>>;
  /// `terms` are over the base scene's coordinates; `lowest`: the worst is the least F_k
  /// (a maximized objective), else the greatest.
  WorstCase(Terms terms, const ConfigurationsSpec* c, bool lowest);
  std::string name() const override { return "worst case"; }
  double Value(const Eigen::VectorXd& q) const override;
  void Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* g) const override;
  /// F_k of each copy.
  Eigen::VectorXd PerCopy(const Eigen::VectorXd& q) const;
  /// KS of the copies' values F.
  double Aggregate(const Eigen::VectorXd& F) const;
  double rho() const { return rho_; }

 private:
  Terms terms_;
  const ConfigurationsSpec* c_;
  bool lowest_;
  double rho_;
};

}  // namespace tangent::design
