#pragma once

// Variants of scenes/peg_in_hole.json for the tests and the benchmarks.

#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "server/scene.h"

namespace tangent::testing {

/// scenes/peg_in_hole.json with its end sphere's poles on the peg's axis: the natural revolved
/// end, whose lowest point, the one the plate and the hole's floor touch, is a pole. The scene
/// file turns them 45° off the axis, from before contacts were followed across poles in their
/// charts (docs/trimming.md, "Peg in hole"; docs/contact.md, "Pole charts").
inline std::unique_ptr<server::Scene> PegWithPolesOnAxis(const std::string& scenes_dir) {
  const std::string path = scenes_dir + "/peg_in_hole.json";
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot read " + path);
  nlohmann::json j = nlohmann::json::parse(file);
  bool found = false;
  for (nlohmann::json& s : j.at("surfaces")) {
    if (s.value("name", "") != "peg_end") continue;
    s.erase("quaternion");
    found = true;
  }
  if (!found) throw std::runtime_error(path + ": no surface named peg_end");
  return server::ParseScene(j.dump(), path + " (poles on the axis)", scenes_dir);
}

}  // namespace tangent::testing
