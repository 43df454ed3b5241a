#pragma once

// The area of a trimmed surface's material (docs/trimming.md, "Area"): ∫∫_D |S_u × S_v| du dv
// over the material D, by Green's theorem as ∮_∂D G dv with G(u, v) = ∫_{u0}^{u} |S_u × S_v|(s, v)
// ds, both integrals by Gauss–Legendre on pieces where the integrand is smooth (the surface's
// knot spans; each trim curve cut where it crosses a knot line). Used to check imported parts
// against Open CASCADE's areas (tests/cad/corpus_test.cc) and in the import report.

#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::nurbs {

/// The area of `surface` over `trim`'s material (the whole domain without a trim).
double TrimmedArea(const NurbsSurface& surface, const TrimmedDomain* trim = nullptr);

}  // namespace tangent::nurbs
