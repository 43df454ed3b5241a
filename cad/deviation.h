#pragma once

// How far an imported face lies from the file's own face (issue 37): the figure the import
// report gives. Open CASCADE types in the interface: for cad/import.cc and the tests.

#include <Geom_Surface.hxx>
#include <Standard_Handle.hxx>

#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::cad {

/// The largest distance (in the surfaces' length unit) from our surface to theirs, over the
/// material of our face: an (n+1) x (n+1) grid of our parameters, edges included, keeping the
/// points `trim` (may be null: the whole domain) holds, and eight points along every trim curve
/// (the boundary is material, and a thin face may hold no grid point). Each point's foot on
/// their surface is found by ShapeAnalysis_Surface (seeded from the previous foot along a grid
/// row), and the distance is measured to their surface's point there. Points off the material
/// are not measured: there the converted surface may run past theirs (a trimmed or bounded
/// surface), and their nearest point is then on their boundary, not a deviation of the face.
double FaceDeviation(const nurbs::NurbsSurface& ours, const nurbs::TrimmedDomain* trim,
                     const Handle(Geom_Surface) & theirs, int n);

}  // namespace tangent::cad
