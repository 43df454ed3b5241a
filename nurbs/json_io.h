#pragma once

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "nurbs/curve.h"
#include "nurbs/surface.h"
#include "nurbs/trim.h"

namespace tangent::nurbs {

/// A malformed curve or surface document. The message starts with the location of the problem
/// as a JSON pointer (e.g. "/knots_u/4") prefixed by the caller's `where` (a file name or the
/// enclosing scene path), then says what is wrong and what was expected.
class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Surface from its JSON form (schema: docs/nurbs.md, "File format"):
/// {"type": "nurbs_surface", "degree_u": p, "degree_v": q, "knots_u": [...], "knots_v": [...],
///  "control_points": [[[x,y,z], ... num_v], ... num_u], "weights": [[w, ...], ...] (optional),
///  "units": "m" | "mm" (optional, default "m"; coordinates are converted to metres)}.
/// @throws ParseError naming the offending field and index.
NurbsSurface SurfaceFromJson(const nlohmann::json& j, const std::string& where = "");
/// Curve of dimension 2 or 3: {"type": "nurbs_curve", "dimension": 2|3, "degree": p,
///  "knots": [...], "control_points": [[...], ...], "weights": [...] (optional), "units"}.
template <int Dim>
NurbsCurve<Dim> CurveFromJson(const nlohmann::json& j, const std::string& where = "");

/// A surface's trimming loops (docs/trimming.md, "File format"):
/// {"outer": [curve, ...] (optional), "holes": [[curve, ...], ...] (optional),
///  "band": β (optional, relative to the domain's diagonal)}, each curve in the surface's (u, v)
/// domain: a {"type": "nurbs_curve", "dimension": 2, ...}, a {"type": "polyline", "points":
/// [[u, v], ...]} or a {"type": "circle", "center": [u, v], "radius": r} (a full rational circle,
/// counter-clockwise; "clockwise": true for the other way). Validated as TrimmedDomain does;
/// *warnings (may be null) gets its warnings. @throws ParseError naming the field for a
/// malformed curve, and the loop and curve for a loop that cannot be used ("where: /holes/1:
/// hole 1 is not closed: curve 0 ends at ...").
TrimmedDomain TrimFromJson(const nlohmann::json& j, const NurbsSurface& surface,
                           const std::string& where = "",
                           std::vector<std::string>* warnings = nullptr);

/// The loops in TrimFromJson's form, every curve as a "nurbs_curve" (after any reversal the
/// domain made).
nlohmann::json ToJson(const TrimmedDomain& trim);

/// Parses text, then reads the surface/curve. JSON syntax errors become ParseError too.
NurbsSurface ParseSurface(const std::string& text, const std::string& where = "");
template <int Dim>
NurbsCurve<Dim> ParseCurve(const std::string& text, const std::string& where = "");
/// Reads a file. @throws ParseError (including when it cannot be opened).
NurbsSurface LoadSurface(const std::string& path);
/// A JSON document from a file (what LoadSurface reads; a scene reads the same document for
/// its surface and its "trim"). @throws ParseError when it cannot be opened or parsed.
nlohmann::json LoadDocument(const std::string& path);

/// The JSON form, in metres, weights included only for rational geometry. Round-trips exactly
/// (doubles are written with 17 significant digits).
nlohmann::json ToJson(const NurbsSurface& surface);
template <int Dim>
nlohmann::json ToJson(const NurbsCurve<Dim>& curve);

}  // namespace tangent::nurbs
