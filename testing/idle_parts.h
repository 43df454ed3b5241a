#pragma once

// The paperclips scene with extra clips declared but in no contact pair, joint, grasp or
// objective (issue 18, "model only what a scene needs"): the servo test's and the benchmark's
// one fixture.

#include <fstream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace tangent::testing {

/// scenes/paperclips.json (in `scenes_dir`) with `extra` idle clips in a row beside the chain,
/// 12 mm apart, as scene JSON text. @throws std::runtime_error when the scene cannot be read.
inline std::string PaperclipsWithIdleClips(const std::string& scenes_dir, int extra) {
  std::ifstream in(scenes_dir + "/paperclips.json");
  if (!in) throw std::runtime_error("cannot read " + scenes_dir + "/paperclips.json");
  nlohmann::json doc = nlohmann::json::parse(in);
  for (int k = 0; k < extra; ++k) {
    const std::string n = std::to_string(k);
    doc["bodies"].push_back(
        {{"name", "idle" + n}, {"position", {76.0 + 12.0 * k, 0.0, 0.0}}, {"mass", 0.0005}});
    doc["surfaces"].push_back(
        {{"name", "idle_wire" + n}, {"body", "idle" + n}, {"type", "paperclip"}});
  }
  return doc.dump();
}

}  // namespace tangent::testing
