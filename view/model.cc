#include "view/model.h"

#include <cmath>

#include <Eigen/Geometry>

#include "nurbs/surface.h"

namespace tangent::view {
namespace {

bool AllFinite(const double* x, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(x[i])) return false;
  }
  return true;
}

/// Quaternions arrive normalized by the server; a tolerance this loose only catches garbage
/// (a zero or wildly scaled quaternion), which would draw a sheared body.
constexpr double kQuaternionNormTolerance = 1e-3;

bool UnitQuaternion(const double* q) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return std::abs(n - 1.0) <= kQuaternionNormTolerance;
}

Eigen::Matrix3d Rotation(const double* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

}  // namespace

ViewModel::ViewModel(const server::Scene& scene) : scene_(scene) {
  const int n = scene.mechanism.num_bodies();
  state_.poses.resize(static_cast<size_t>(n));
  for (int b = 0; b < n; ++b) {
    const optimizer::Vector7d& x = scene.mechanism.body(b).pose;
    for (int i = 0; i < 7; ++i) state_.poses[static_cast<size_t>(b)][static_cast<size_t>(i)] = x[i];
  }
}

bool ViewModel::Reject(std::string* why, std::string reason) {
  ++rejected_;
  if (why) *why = std::move(reason);
  return false;
}

bool ViewModel::Apply(const scene_state_t& m, std::string* why) {
  const int n = scene_.mechanism.num_bodies();
  if (m.num_bodies != n) {
    return Reject(why, "scene_state_t.num_bodies is " + std::to_string(m.num_bodies) +
                           ", the loaded scene \"" + scene_.name + "\" has " + std::to_string(n) +
                           " bodies (is the view on the server's scene?)");
  }
  for (int b = 0; b < n; ++b) {
    const size_t k = static_cast<size_t>(b);
    if (m.names[k] != scene_.mechanism.body(b).name) {
      return Reject(why, "scene_state_t.names[" + std::to_string(b) + "] is \"" + m.names[k] +
                             "\", the loaded scene has \"" + scene_.mechanism.body(b).name + "\"");
    }
    if (!AllFinite(m.position[k].data(), 3) || !AllFinite(m.orientation[k].data(), 4) ||
        !UnitQuaternion(m.orientation[k].data())) {
      return Reject(why, "scene_state_t: body " + std::to_string(b) +
                             " has a non-finite position or a non-unit orientation");
    }
  }
  if (!AllFinite(m.grasp_target, 3)) {
    return Reject(why, "scene_state_t.grasp_target is not finite");
  }
  for (int b = 0; b < n; ++b) {
    const size_t k = static_cast<size_t>(b);
    for (size_t i = 0; i < 3; ++i) state_.poses[k][i] = m.position[k][i];
    for (size_t i = 0; i < 4; ++i) state_.poses[k][3 + i] = m.orientation[k][i];
  }
  state_.grasp_W = Eigen::Vector3d(m.grasp_target[0], m.grasp_target[1], m.grasp_target[2]);
  state_.utime = m.utime;
  ++version_;
  return true;
}

bool ViewModel::Apply(const contact_states_t& m, std::string* why) {
  const int num_surfaces = static_cast<int>(scene_.surfaces.size());
  std::vector<ViewContact> contacts;
  contacts.reserve(m.contacts.size());
  for (size_t c = 0; c < m.contacts.size(); ++c) {
    const contact_state_t& s = m.contacts[c];
    const std::string at = "contact_states_t.contacts[" + std::to_string(c) + "]";
    if (s.surface_a < 0 || s.surface_a >= num_surfaces || s.surface_b < 0 ||
        s.surface_b >= num_surfaces) {
      return Reject(why, at + ": surface index out of range (the scene has " +
                             std::to_string(num_surfaces) + " surfaces)");
    }
    if (!AllFinite(s.params, 4) || !AllFinite(s.point_a, 3) || !AllFinite(s.point_b, 3) ||
        !std::isfinite(s.distance) || !std::isfinite(s.force)) {
      return Reject(why, at + ": a field is not finite");
    }
    ViewContact v;
    v.surface_a = s.surface_a;
    v.surface_b = s.surface_b;
    v.p_WA = Eigen::Vector3d(s.point_a[0], s.point_a[1], s.point_a[2]);
    v.p_WB = Eigen::Vector3d(s.point_b[0], s.point_b[1], s.point_b[2]);
    v.distance = s.distance;
    v.force = s.force;
    // The normal of surface a at its extremal point, exact from the NURBS and the body's pose.
    const server::SceneSurface& a = scene_.surfaces[static_cast<size_t>(s.surface_a)];
    const nurbs::SurfacePoint p = a.surface.Evaluate(s.params[0], s.params[1], 2);
    const Eigen::Vector3d n_B = nurbs::UnitNormal(a.surface, s.params[0], s.params[1], p);
    v.n_W = Rotation(&state_.poses[static_cast<size_t>(a.body)][3]) * n_B;
    const Eigen::Vector3d d_W = v.p_WB - v.p_WA;
    if (d_W.norm() > 0.0 && d_W.dot(v.n_W) * v.distance < 0.0) v.n_W = -v.n_W;
    contacts.push_back(v);
  }
  state_.contacts = std::move(contacts);
  ++version_;
  return true;
}

bool ViewModel::Apply(const wrench_t& m, std::string* why) {
  if (!AllFinite(m.force, 3)) return Reject(why, "wrench_t.force is not finite");
  const Eigen::Vector3d f_D(m.force[0], m.force[1], m.force[2]);
  state_.force_W = scene_.device.R_WD * f_D;
  state_.wrench_state = m.state;
  state_.has_force = true;
  ++version_;
  return true;
}

bool ViewModel::Apply(const device_state_t& m, std::string* why) {
  if (!AllFinite(m.orientation, 4) || !UnitQuaternion(m.orientation)) {
    return Reject(why, "device_state_t.orientation is not a unit quaternion");
  }
  const Eigen::Quaterniond q_WS(
      Eigen::Quaterniond(scene_.device.R_WD) *
      Eigen::Quaterniond(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3])
          .normalized());
  state_.tool_q_W = Eigen::Vector4d(q_WS.w(), q_WS.x(), q_WS.y(), q_WS.z());
  state_.has_tool = true;
  ++version_;
  return true;
}

bool ViewModel::Apply(const loop_stats_t& m, std::string* why) {
  const double fields[] = {m.loop_rate_hz, m.compute_p50_us, m.compute_p99_us, m.max_violation};
  if (!AllFinite(fields, 4)) return Reject(why, "loop_stats_t: a field is not finite");
  state_.stats = {m.loop_rate_hz, m.compute_p50_us, m.compute_p99_us, m.max_violation,
                  m.num_contacts};
  state_.has_stats = true;
  ++version_;
  return true;
}

nlohmann::json StateMessage(const ViewState& s) {
  auto vec = [](const Eigen::Vector3d& x) { return nlohmann::json::array({x[0], x[1], x[2]}); };
  nlohmann::json contacts = nlohmann::json::array();
  for (const ViewContact& c : s.contacts) {
    contacts.push_back({{"a", c.surface_a},
                        {"b", c.surface_b},
                        {"pa", vec(c.p_WA)},
                        {"pb", vec(c.p_WB)},
                        {"n", vec(c.n_W)},
                        {"d", c.distance},
                        {"f", c.force}});
  }
  nlohmann::json j = {{"type", "state"},
                      {"utime", s.utime},
                      {"poses", s.poses},
                      {"grasp", vec(s.grasp_W)},
                      {"contacts", std::move(contacts)}};
  if (s.has_tool) {
    j["tool"] = {s.tool_q_W[0], s.tool_q_W[1], s.tool_q_W[2], s.tool_q_W[3]};
  }
  if (s.has_force) {
    j["force"] = vec(s.force_W);
    j["wrench_state"] = s.wrench_state;
  }
  if (s.has_stats) {
    j["stats"] = {{"rate_hz", s.stats.loop_rate_hz},
                  {"p50_us", s.stats.compute_p50_us},
                  {"p99_us", s.stats.compute_p99_us},
                  {"violation", s.stats.max_violation},
                  {"contacts", s.stats.num_contacts}};
  }
  return j;
}

}  // namespace tangent::view
