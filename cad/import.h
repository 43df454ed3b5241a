#pragma once

// CAD import (docs/cad.md): STEP (AP203, AP214, AP242) and IGES files read by Open CASCADE,
// every face converted to a trimmed NURBS surface of ours. With cad/deviation.h the only code
// outside tests and benchmarks that includes Open CASCADE; the rest of Tangent builds without it.
//
// Each face is converted by BRepBuilderAPI_NurbsConvert (planes, cylinders, cones, spheres,
// tori, revolutions, extrusions, offsets and B-splines alike) into a B-spline surface, made
// non-periodic, and its wires become trimming loops: the outer wire the outer loop and the others
// holes, each edge's pcurve on the face converted to a 2-D B-spline over the edge's range, in
// the wire's order and orientation (seams appear once per side, as OCCT gives them). A face
// whose orientation is reversed in its shell has its u direction reversed (surface and loops
// alike), so that S_u × S_v points out of the solid. Lengths come out in metres whatever the
// file's unit. Solids (or, without solids, shells and free faces) become bodies. The files are
// read through XCAF, so the names and colours they give solids and faces come along.

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::cad {

/// A file that cannot be imported at all (missing, unreadable, not STEP or IGES, no faces):
/// "part.step: not a STEP file (the reader says: ...)".
class ImportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ImportedFace {
  std::string name;  ///< "<body> face <k>"
  std::string kind;  ///< the face's surface before conversion: plane, cylinder, cone, ...
  nurbs::NurbsSurface surface;
  std::optional<nurbs::TrimmedDomain> trim;
  /// The largest distance (m) between our surface and Open CASCADE's: our evaluation against
  /// theirs of the converted surface at the same parameters (a grid), and the face's material
  /// against the file's own surface (cad/deviation.h's FaceDeviation).
  double deviation = 0.0;
  bool reversed = false;  ///< the face was reversed in its shell (its u direction flipped here)
  std::string label;      ///< the file's name for the face (XCAF), empty when it has none
  /// The file's surface colour for the face (sRGB, 0..1), else its body's; none if neither.
  std::optional<std::array<double, 3>> colour;
};

struct ImportedBody {
  std::string name;   ///< "solid <k>", "shell <k>" or "faces": stable whatever the file names
  std::string label;  ///< the file's name for the solid or its product (XCAF), empty if none
  std::optional<std::array<double, 3>> colour;  ///< the file's colour for it (sRGB, 0..1)
  std::vector<ImportedFace> faces;
};

struct ImportReport {
  std::vector<std::pair<std::string, int>> faces_by_kind;
  int loops = 0, faces = 0, skipped = 0;
  double largest_deviation = 0.0;
  std::vector<std::string> warnings;  ///< faces skipped and why, loops reversed, healing done
};

struct ImportedPart {
  std::string path;
  std::vector<ImportedBody> bodies;
  ImportReport report;
};

struct ImportOptions {
  /// Heal the shape (ShapeFix_Shape) before conversion.
  bool heal = true;
  /// β of the trimming loops' certified band, relative to each face's domain diagonal.
  double trim_band = 1e-4;
  /// Parameters per direction at which the deviation against Open CASCADE is measured.
  int deviation_grid = 12;
  /// Run Open CASCADE in a child process (fork) and take the part back as our own JSON: a
  /// malformed file can crash Open CASCADE's readers (the import fuzzer found a STEP face bound
  /// pointing at the wrong entity dereference null in StepShape_FaceBound::Bound), and that
  /// must be an ImportError, not the caller's crash. Off only where a caller needs the
  /// reader's coverage in its own process (the fuzzer's in-process mode).
  bool isolate = true;
  /// With isolate: an import still running after this long is stopped (the child killed) and
  /// is an ImportError, so a file that sends Open CASCADE into an endless loop cannot hang the
  /// caller. The 102-face plate of bench/cad_load imports in under a second.
  double timeout_seconds = 120.0;
};

/// Reads a STEP (.step, .stp) or IGES (.igs, .iges) file. A face that cannot be converted is
/// skipped with a warning naming it; the rest of the part is imported. @throws ImportError (also
/// when Open CASCADE crashed on the file: "part.step: Open CASCADE crashed reading it (signal
/// 11, Segmentation fault)").
ImportedPart ImportCad(const std::string& path, const ImportOptions& options = {});

/// The report as text lines (tangent-import prints it).
std::vector<std::string> ReportLines(const ImportedPart& part);

}  // namespace tangent::cad
