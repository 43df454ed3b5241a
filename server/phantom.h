#pragma once

// The simulated PHANToM of tangent-phantom (issue 6), without I/O: a scripted hand drives the
// stylus through a hand impedance; the device has mass, damping, force saturation and workspace
// limits and applies the wrench the server sends; statistics include an energy (passivity) check.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace tangent::server {

/// Where the hand wants the stylus tip (device frame, m) at time t (s).
class HandTrajectory {
 public:
  /// Built-in: "drag" (lift 6 mm, then circles of 4 mm), "circle", "pull" (±6 mm along y),
  /// "hold". @throws std::invalid_argument naming the unknown trajectory.
  static HandTrajectory BuiltIn(const std::string& name);
  /// CSV with header "t,x,y,z" (s, m), rows increasing in t. @throws std::invalid_argument with
  /// the file and line of the first bad row.
  static HandTrajectory FromCsv(const std::string& text, const std::string& where);
  Eigen::Vector3d At(double t) const;
  const std::string& name() const { return name_; }
  /// Beyond its end the trajectory repeats from `from` (s) to its end (soak runs); "drag" is
  /// periodic from 3 s (whole circles), so it loops without a step. A negative value holds the
  /// end (the default). @throws std::invalid_argument if `from` is not before the end.
  void LoopFrom(double from);

 private:
  std::string name_;
  double loop_from_ = -1.0;
  std::vector<double> t_;
  std::vector<Eigen::Vector3d> x_;
};

struct DeviceModelOptions {
  double mass = 0.045;     ///< kg, apparent mass at the tip (Touch-class)
  double damping = 0.05;   ///< N s/m, the device's own friction
  double max_force = 3.3;  ///< N, saturation of the rendered force
  Eigen::Vector3d workspace = Eigen::Vector3d(0.08, 0.06, 0.035);  ///< half extents, m
  double hand_stiffness = 400.0;                                   ///< N/m
  double hand_damping = 8.0;                                       ///< N s/m
};

/// Semi-implicit Euler of m ẍ = F_hand + sat(F_server) − b ẋ, clamped to the workspace.
class DeviceModel {
 public:
  explicit DeviceModel(const DeviceModelOptions& o = {}) : o_(o) {}
  /// One step of dt with the hand at `hand` (moving at `hand_velocity`) and the server's force.
  /// @return the force applied after saturation.
  Eigen::Vector3d Step(double dt, const Eigen::Vector3d& hand, const Eigen::Vector3d& hand_velocity,
                       const Eigen::Vector3d& server_force);
  const Eigen::Vector3d& position() const { return x_; }
  const Eigen::Vector3d& velocity() const { return v_; }
  /// ∫ F_server · v dt: energy the server's force has put into the device (J). A passive
  /// environment gives back at most what it stored: bounded above by its stored energy.
  double energy_from_server() const { return energy_; }
  double max_applied_force() const { return max_force_; }

 private:
  DeviceModelOptions o_;
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero();
  double energy_ = 0.0, max_force_ = 0.0;
};

/// What a device driver does with the wrenches it receives (docs/server.md, "What a device
/// driver must do"): it renders the latest wrench while wrenches keep coming; when none has come
/// for `timeout` it ramps the rendered force to zero by itself; and it never changes the
/// rendered force faster than `rate`, so a resumed stream ramps back too.
class DriverWatchdog {
 public:
  /// @param timeout s without a wrench before the driver acts (> 0)
  /// @param rate N/s, the driver's own force-rate limit (> 0)
  /// @throws std::invalid_argument naming the bad value.
  DriverWatchdog(double timeout, double rate);
  /// The force to render at time t (s) after a device step of dt (s): `wrench` is the latest
  /// wrench's force (N), received at `received` (s; negative: none yet).
  Eigen::Vector3d Step(double t, double dt, const Eigen::Vector3d& wrench, double received);
  int64_t trips() const { return trips_; }  ///< times the watchdog fired
  bool starved() const { return starved_; }

 private:
  double timeout_, rate_;
  Eigen::Vector3d rendered_ = Eigen::Vector3d::Zero();
  bool starved_ = false;
  int64_t trips_ = 0;
};

/// Percentiles of a sample (sorted copy).
struct Percentiles {
  double p50 = 0, p99 = 0, p999 = 0, max = 0;
  size_t n = 0;
  static Percentiles Of(std::vector<double> v);
};

/// Force history → oscillation measure: RMS of the second difference of the force (N), which
/// a smooth contact keeps small and a chattering coupling makes large.
double ForceRoughness(const std::vector<Eigen::Vector3d>& f);

}  // namespace tangent::server
