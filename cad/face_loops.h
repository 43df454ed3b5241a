#pragma once

// A face's trimming loops from its wires, within the file's own tolerances (docs/cad.md, step 4;
// issue 37). Internal to tangent_cad: it includes Open CASCADE.
//
// Real files carry what the systems that wrote them accept within each edge's and vertex's
// tolerance (BRep_Tool::Tolerance): pcurves that run a little past the surface's domain, wires
// whose pcurves do not quite meet, pcurves given one period away on a closed surface. Each such
// repair is made only where the part moves by no more than that tolerance in space, measured on
// the surface; a face whose loops are wrong beyond it is refused with the amount.

#include <Geom_BSplineSurface.hxx>
#include <TopoDS_Face.hxx>

#include <optional>
#include <string>
#include <vector>

#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::cad {

struct FaceLoops {
  std::optional<nurbs::TrimLoop> outer;
  std::vector<nurbs::TrimLoop> holes;
  /// What was repaired within the file's tolerance (round-off, a part in 1e12 of the domain,
  /// is not counted). Distances are in space, on the surface.
  struct Repairs {
    int clamped = 0;          ///< pcurves that left the domain, clamped into it
    double clamped_by = 0.0;  ///< the most such a pcurve moved (m)
    int shifted = 0;          ///< pcurves given one period away on a closed surface
    int gaps = 0;             ///< junctions closed by more than 1e-6 of the domain's diagonal
    double gaps_by = 0.0;     ///< the widest of them (m)
    int joined = 0;           ///< of those, joined by a piece of their own (across a pole)
    bool any() const { return clamped + shifted + gaps > 0; }
    /// "2 pcurves clamped into the domain (by up to 3.2e-06 m), 1 gap closed (2.98e-06 m)".
    std::string Describe() const;
  } repairs;
};

/// The loops of `face` (already converted to a B-spline surface `bs` with pcurves) in the
/// parameters of `surface` (ours, made from `bs`, its u reversed when `flip_u`). @throws
/// std::runtime_error naming what is wrong beyond the file's tolerance, and by how much.
FaceLoops BuildFaceLoops(const TopoDS_Face& face, const Handle(Geom_BSplineSurface) & bs,
                         bool flip_u, const nurbs::NurbsSurface& surface);

}  // namespace tangent::cad
