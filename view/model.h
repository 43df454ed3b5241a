#pragma once

// The view's picture of a running scene, built from the server's LCM messages (or a log of them)
// and turned into the JSON the browser draws. Every message is untrusted input: indices out of
// range, non-finite numbers or a scene other than the one loaded are rejected with a reason and
// counted, never drawn and never a crash.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "server/scene.h"
#include "tangent/contact_states_t.hpp"
#include "tangent/device_state_t.hpp"
#include "tangent/loop_stats_t.hpp"
#include "tangent/scene_state_t.hpp"
#include "tangent/wrench_t.hpp"

namespace tangent::view {

/// One contact as drawn: both extremal points, the normal of surface a there (world frame, unit,
/// turned toward b when the surfaces are apart), the signed distance and the force.
struct ViewContact {
  int surface_a = 0, surface_b = 0;
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero(), p_WB = Eigen::Vector3d::Zero();  ///< metres
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();
  double distance = 0.0;  ///< metres, < 0 interpenetrating
  double force = 0.0;     ///< newtons
};

struct ViewStats {
  double loop_rate_hz = 0.0, compute_p50_us = 0.0, compute_p99_us = 0.0;
  double max_violation = 0.0;  ///< metres, over the server's last statistics window
  int num_contacts = 0;
};

struct ViewState {
  int64_t utime = -1;  ///< server time of the last body poses applied, µs (−1: none yet)
  /// X_WB of every body: position (metres) then unit quaternion (w, x, y, z).
  std::vector<std::array<double, 7>> poses;
  Eigen::Vector3d grasp_W = Eigen::Vector3d::Zero();  ///< the device's tool point in the world
  std::vector<ViewContact> contacts;
  bool has_tool = false;
  Eigen::Vector4d tool_q_W = Eigen::Vector4d(1, 0, 0, 0);  ///< stylus orientation in the world
  bool has_force = false;
  Eigen::Vector3d force_W = Eigen::Vector3d::Zero();  ///< force rendered on the hand, N, world
  int wrench_state = 0;                               ///< wrench_t.state of the last wrench
  bool has_stats = false;
  ViewStats stats;
};

/// Applies the server's messages to a ViewState for one scene.
class ViewModel {
 public:
  /// @param scene kept by reference; must outlive the model.
  explicit ViewModel(const server::Scene& scene);

  /// Each returns false and sets *why (naming the field) when the message cannot be drawn; the
  /// state is then unchanged.
  bool Apply(const scene_state_t& m, std::string* why);
  bool Apply(const contact_states_t& m, std::string* why);
  bool Apply(const wrench_t& m, std::string* why);
  bool Apply(const device_state_t& m, std::string* why);
  bool Apply(const loop_stats_t& m, std::string* why);

  const ViewState& state() const { return state_; }
  /// +1 on every change: the sender compares it to decide whether a frame is due.
  uint64_t version() const { return version_; }
  int64_t rejected() const { return rejected_; }

 private:
  bool Reject(std::string* why, std::string reason);

  const server::Scene& scene_;
  ViewState state_;
  uint64_t version_ = 0;
  int64_t rejected_ = 0;
};

/// {"type":"state", "utime", "poses", "grasp", "contacts":[{a, b, pa, pb, n, d, f}], "tool"?,
/// "force"?, "stats"?}, all lengths in metres.
nlohmann::json StateMessage(const ViewState& state);

}  // namespace tangent::view
