// libFuzzer target: the scene parser (server/scene.h ParseScene) on arbitrary text.
// A scene names NURBS files relative to its own folder; the base folder here is scenes/, so
// inputs mutated from the example scenes load their real surfaces. Every outcome is a parsed
// scene or a SceneError naming the file, the JSON pointer and the problem; any other exception,
// crash, hang or sanitizer report is a finding (docs/reliability.md "Fuzzing"). The offset
// meshes are left out: building and certifying them costs seconds an input (their size is
// bounded by the tessellator's grid cap, 4097 lines each way).

#include <cstddef>
#include <cstdint>
#include <string>

#include "server/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    tangent::server::SceneLoadOptions options;
    options.offset_meshes = false;  // certified meshes cost seconds an input (see scene.h)
    const auto scene = tangent::server::ParseScene(text, "fuzz.json", TANGENT_SCENES_DIR, options);
    // A scene that loads is usable: every surface evaluates.
    for (const auto& s : scene->surfaces) (void)s.surface.Evaluate(0.5, 0.5);  // clamped
  } catch (const tangent::server::SceneError&) {
  }
  return 0;
}
