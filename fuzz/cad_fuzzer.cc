// libFuzzer target: CAD import (cad/import.h ImportCad) on arbitrary bytes. The first byte picks
// the format (even: STEP, odd: IGES), the rest is the file, written to a temporary path that the
// importer reads as a user's file would be read. Every outcome is an imported part or an
// ImportError naming the file and the problem (a face that fails conversion is a named warning,
// the rest imported); any other exception, crash, hang or sanitizer report in our code is a
// finding (docs/reliability.md "Fuzzing"). Seeds: parts Open CASCADE writes (cad_seeds.cc).
//
// The import runs as users run it, Open CASCADE in a child process (ImportOptions::isolate):
// Open CASCADE's STEP reader crashes on some malformed files (the first 60 s found one, kept in
// regressions/cad/), which must come back as an ImportError. libFuzzer therefore sees the
// coverage of our side only (the result read back, the checks below); the mutations still reach
// every section of the seed files, and a crash or sanitizer report in our code stops the run.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "cad/import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const bool iges = (data[0] & 1) != 0;
  const std::string path =
      "/tmp/tangent-cad-fuzz-" + std::to_string(getpid()) + (iges ? ".igs" : ".step");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    tangent::cad::ImportOptions options;
    options.timeout_seconds = 5.0;  // under libFuzzer's own hang limit (10 s)
    const tangent::cad::ImportedPart part = tangent::cad::ImportCad(path, options);
    // A part that imports is usable: every face evaluates, every trim classifies.
    for (const auto& body : part.bodies) {
      for (const auto& face : body.faces) {
        (void)face.surface.Evaluate(0.5, 0.5);  // clamped
        if (face.trim) (void)face.trim->Contains({0.5, 0.5});
      }
    }
    (void)tangent::cad::ReportLines(part);
  } catch (const tangent::cad::ImportError&) {
  }
  std::remove(path.c_str());
  return 0;
}
