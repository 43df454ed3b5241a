// tangent-import PART.step|PART.igs -o part.json (docs/cad.md): a CAD part as a Tangent scene —
// one moving body per solid, each face a trimmed NURBS surface on it — and a report of what was
// imported: faces by surface type, loops, the deviation from Open CASCADE's evaluation, anything
// skipped and why. Exit status 1 when the file cannot be imported at all.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cad/import.h"
#include "nurbs/json_io.h"

namespace {

// A scene (docs/server.md) holding the part: its bodies free, its faces on them, the grasp on
// the first body. Contacts between parts are for the scene's author to declare.
nlohmann::json SceneOf(const tangent::cad::ImportedPart& part, int64_t device_id) {
  nlohmann::json scene;
  scene["name"] = std::filesystem::path(part.path).stem().string();
  scene["comment"] = "imported from " + part.path + " by tangent-import";
  scene["length_unit"] = "m";
  nlohmann::json bodies = nlohmann::json::array(), surfaces = nlohmann::json::array();
  for (const tangent::cad::ImportedBody& b : part.bodies) {
    nlohmann::json body = {{"name", b.name}, {"mass", 0.1}};
    // The file's names and colours, kept for the reader and for viewers (the scene loader
    // does not need them).
    if (!b.label.empty()) body["label"] = b.label;
    if (b.colour) body["colour"] = *b.colour;
    bodies.push_back(body);
    for (const tangent::cad::ImportedFace& f : b.faces) {
      nlohmann::json s = {{"name", f.name},
                          {"body", b.name},
                          {"type", "nurbs"},
                          {"nurbs", tangent::nurbs::ToJson(f.surface)}};
      if (f.trim) s["trim"] = tangent::nurbs::ToJson(*f.trim);
      if (!f.label.empty()) s["label"] = f.label;
      if (f.colour) s["colour"] = *f.colour;
      surfaces.push_back(s);
    }
  }
  scene["bodies"] = bodies;
  scene["surfaces"] = surfaces;
  scene["grasp"] = {{"body", part.bodies.front().name}};
  // The device tangentd serves is named, never guessed (docs/server.md "Device sessions").
  scene["device"] = {{"id", device_id}};
  return scene;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tangent-import: a STEP or IGES part as a Tangent scene (docs/cad.md)"};
  std::string input, output;
  double band = 1e-4;
  bool quiet = false;
  int64_t device_id = 1;
  app.add_option("part", input, "the STEP (.step, .stp) or IGES (.igs, .iges) file")->required();
  app.add_option("-o,--output", output, "the scene file to write (default: PART.json beside it)");
  app.add_option("--trim-band", band, "certified band of the trimming loops, relative")
      ->check(CLI::Range(1e-8, 1e-2));
  app.add_flag("-q,--quiet", quiet, "print only warnings and errors");
  app.add_option("--device-id", device_id,
                 "the device the scene names for tangentd to serve (device.id; tangent-phantom's "
                 "default is 1)");
  CLI11_PARSE(app, argc, argv);
  if (output.empty()) output = std::filesystem::path(input).replace_extension(".json").string();
  try {
    tangent::cad::ImportOptions options;
    options.trim_band = band;
    const tangent::cad::ImportedPart part = tangent::cad::ImportCad(input, options);
    for (const std::string& line : tangent::cad::ReportLines(part)) {
      if (!quiet || line.rfind("warning:", 0) == 0) std::printf("%s\n", line.c_str());
    }
    std::ofstream out(output);
    if (!out) {
      std::fprintf(stderr, "tangent-import: cannot write %s\n", output.c_str());
      return 1;
    }
    out << SceneOf(part, device_id).dump(1) << "\n";
    if (!quiet) std::printf("written to %s\n", output.c_str());
  } catch (const tangent::cad::ImportError& e) {
    std::fprintf(stderr, "tangent-import: %s\n", e.what());
    return 1;
  }
  return 0;
}
