#pragma once

// The spatial four-bar (scenes/fourbar_point.json) with k extra contacts (issue 18, how cost
// grows): k balls on the crank, centred on its axis one above another, each resting on its own
// small plate on the ground. The crank turns about that axis, so every ball spins in place on
// its plate: k contacts that stay active (β = 0, tracked) whatever the hand does, without
// blocking the mechanism. Their normals lie along the axis, which the crank's revolute joint
// already holds: each adds a row the joint makes redundant (rank-deficient, as the solver must
// take). The balls' poles are turned off the axis (a contact at a pole is not yet held
// reliably: docs/trimming.md).

#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace tangent::testing {

inline std::string FourBarWithContacts(const std::string& scenes_dir, int extra) {
  std::ifstream in(scenes_dir + "/fourbar_point.json");
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str());
  doc["name"] = "four-bar + " + std::to_string(extra) + " contacts";
  doc["offset"] = {{"tolerance", 5e-5}, {"margin", 2.5e-4}};
  // Spheres of neglect wider than where a resting ball's offsets overlap (√(4 x 0.25 mm x 5 mm)
  // ≈ 2.2 mm), as in the peg-in-hole scene: the global stage skips them.
  doc["global_stage"] = {{"neglect_radius", 0.004}};
  const double r = 0.005, gap = 0.015;  // m: ball radius, spacing along the axis
  for (int k = 0; k < extra; ++k) {
    const std::string n = std::to_string(k);
    const double z = -0.03 - gap * k;  // below the crank's pivot
    doc["surfaces"].push_back({{"name", "ball" + n},
                               {"body", "crank"},
                               {"type", "sphere"},
                               {"radius", r},
                               {"position", {0, 0, z}},
                               {"quaternion", {0.9238795325112867, -0.3826834323650898, 0, 0}}});
    doc["surfaces"].push_back({{"name", "plate" + n},
                               {"body", "ground"},
                               {"type", "plane_patch"},
                               {"origin", {-0.01, -0.01, z - r}},
                               {"edge_u", {0.02, 0, 0}},
                               {"edge_v", {0, 0.02, 0}}});
    doc["contacts"].push_back(
        {{"a", "plate" + n}, {"b", "ball" + n}, {"kind", "unilateral"}, {"max_contacts", 1}});
  }
  return doc.dump();
}

}  // namespace tangent::testing
