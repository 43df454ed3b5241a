#pragma once

// A chain of paperclips as scene JSON (issue 18, how cost grows): clip 0 held fixed, clips
// 1..n each hooked on the one below as in scenes/paperclips.json (contact::testing::
// PaperclipChainPoses: every other clip turned 90° about y, each small bend hanging on the top
// point of the clip below), a non-penetration pair between neighbours, the hand grasping the
// top of the last clip.

#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace tangent::testing {

/// @param moving clips hanging from the fixed one (≥ 1) @param max_contacts per pair
inline std::string PaperclipChainScene(int moving, int max_contacts) {
  const double mm = 1e-3;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d top(-2.5 * mm, 23 * mm, 0), bend(-1.75 * mm, -6 * mm, 0);
  const Eigen::Vector3d inside(0, -2.35 * mm, 0);
  nlohmann::json doc = {{"name", std::to_string(moving + 1) + " paperclips"},
                        {"length_unit", "mm"},
                        {"least_astonishment", 1},
                        {"offset", {{"tolerance", 0.02}, {"margin", 0.25}}}};
  doc["bodies"] = nlohmann::json::array();
  doc["surfaces"] = nlohmann::json::array();
  doc["contacts"] = nlohmann::json::array();
  Eigen::Quaterniond R = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (int k = 0; k <= moving; ++k) {
    const std::string n = std::to_string(k);
    nlohmann::json body = {{"name", "clip" + n}};
    if (k == 0) {
      body["fixed"] = true;
    } else {
      // Hook clip k's small bend on clip k−1's top point.
      const Eigen::Vector3d hook = R * top + t;
      R = k % 2 ? turn : Eigen::Quaterniond::Identity();
      t = hook - inside - R * bend;
      body["position"] = {t.x() / mm, t.y() / mm, t.z() / mm};
      body["quaternion"] = {R.w(), R.x(), R.y(), R.z()};
      body["mass"] = 0.0005;
      body["inertia"] = {4.5e-08, 4e-09, 4.9e-08};
    }
    doc["bodies"].push_back(body);
    doc["surfaces"].push_back({{"name", "wire" + n}, {"body", "clip" + n}, {"type", "paperclip"}});
    if (k > 0) {
      doc["contacts"].push_back({{"a", "wire" + std::to_string(k - 1)},
                                 {"b", "wire" + n},
                                 {"kind", "unilateral"},
                                 {"max_contacts", max_contacts}});
    }
  }
  doc["grasp"] = {{"body", "clip" + std::to_string(moving)},
                  {"point", {-2.5, 23, 0}},
                  {"hold_orientation", 0.0001}};
  doc["device"] = {{"stiffness", 300}, {"damping", 1.0}, {"max_force", 3.3}};
  return doc.dump();
}

}  // namespace tangent::testing
