#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "contact/placed.h"

namespace tangent::optimizer {

using contact::BodyPose;
using contact::Vector7d;

/// A rigid body of a mechanism: fixed (a constant pose X_WB) or moving (7 coordinates in the
/// scene's coordinate vector). Mass and rotational inertia (body frame, at the origin of B) set
/// the kinetic-energy metric of least astonishment; rigidity scales it (seed 002 §11).
struct Body {
  std::string name;
  bool fixed = false;
  Vector7d pose = (Vector7d() << 0, 0, 0, 1, 0, 0, 0).finished();  ///< initial or fixed pose
  double mass = 1.0;                                               ///< kg
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity() * 1e-3;    ///< kg m², frame B
  double rigidity = 1.0;  ///< multiplies the body's block of the metric (≥ 0)
};

/// Bodies and the layout of the coordinate vector q: moving bodies stacked in the order they
/// were added, 7 coordinates each, [p_WB, Q_WB].
class Mechanism {
 public:
  /// @return the body's index (used by joints and goals). @throws std::invalid_argument on a
  /// non-finite pose, a zero quaternion, non-positive mass or a non-symmetric inertia.
  int AddBody(Body body);

  int num_bodies() const { return static_cast<int>(bodies_.size()); }
  int num_moving() const { return num_moving_; }
  int num_coordinates() const { return 7 * num_moving_; }
  const Body& body(int i) const { return bodies_[static_cast<size_t>(i)]; }
  /// Offset of the body's coordinates in q, or −1 for a fixed body.
  int offset(int i) const { return offsets_[static_cast<size_t>(i)]; }

  /// The initial coordinate vector (moving bodies' poses).
  Eigen::VectorXd InitialCoordinates() const;
  /// Poses of all bodies for coordinates q (fixed bodies keep theirs). Allocation free when
  /// `poses` already has num_bodies() entries; fixed bodies' entries are written only when the
  /// vector is sized, so pass a vector this mechanism fills (not one of another's size).
  void Poses(const Eigen::VectorXd& q, std::vector<BodyPose>* poses) const;
  /// Kinetic-energy metric diagonal blocks (7 x 7 per moving body, rigidity applied), for
  /// ½ q̇ᵀ M q̇ = Σ ½ m |ṗ|² + ½ w_Bᵀ I_B w_B with w_B = G(Q) Q̇ at q.
  void Metric(const Eigen::VectorXd& q, Eigen::MatrixXd* M) const;
  /// The same metric as one 7 x 7 block per moving body (in coordinate order). Allocation free
  /// when *blocks already has num_moving() entries.
  void MetricBlocks(const Eigen::VectorXd& q,
                    std::vector<Eigen::Matrix<double, 7, 7>>* blocks) const;

 private:
  std::vector<Body> bodies_;
  std::vector<int> offsets_;
  int num_moving_ = 0;
};

}  // namespace tangent::optimizer
