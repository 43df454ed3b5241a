#pragma once

// What the browser draws, made once per scene: every surface's certified tessellation with its
// trimmed-away cells cut (nurbs::CutAlongTrim), exact unit normals from the surface, a colour per
// body, and a content hash so a browser that has a mesh already is not sent it again.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/scene.h"

namespace tangent::view {

/// One surface's display mesh, in its body's frame (metres).
struct DisplayMesh {
  std::string surface;  ///< the scene's surface name
  int surface_index = 0;
  int body = 0;
  std::vector<float> positions;   ///< 3 per vertex, body frame, metres
  std::vector<float> normals;     ///< 3 per vertex, the unit normal (body frame; limit at poles)
  std::vector<float> uv;          ///< 2 per vertex, the surface parameters (not sent)
  std::vector<uint32_t> indices;  ///< 3 per triangle
  std::array<float, 3> colour{};  ///< linear RGB in [0, 1]
  double error_bound = 0.0;       ///< the tessellation's certified bound, metres
  std::string hash;               ///< 16 hex digits, FNV-1a 64 of the arrays and the colour
};

/// Display meshes of all surfaces of `scene`, each within `tolerance` metres of its surface
/// (certified; a surface that needs more than max_lines lines gets a larger, reported bound).
/// Trimmed surfaces are cut along their trims on a grid whose cell chords are at most
/// `trim_cell` metres (0: 10 × tolerance), the cells a trim crosses split three times, so a hole
/// shows with its rim to 1/8 of such a cell; no material is ever left out. Their bound is then
/// at most twice the grid's (reported in error_bound).
/// @throws std::invalid_argument when tolerance is not positive.
std::vector<DisplayMesh> BuildDisplayMeshes(const server::Scene& scene, double tolerance,
                                            double trim_cell = 0.0, int max_lines = 513);

/// A display tolerance for a scene: 1/2000 of its size at rest, the size being the diagonal of
/// the bounding box of its surfaces' control points at the initial poses.
double DefaultDisplayTolerance(const server::Scene& scene);

/// The body colour used by the view (a fixed palette, so figures stay the same from run to run).
std::array<float, 3> BodyColour(int body);

/// {"type":"mesh", "hash", "surface", "body", "positions", "normals", "indices", "colour",
/// "error_bound"}: one mesh as sent to a browser that asked for it by hash.
nlohmann::json MeshMessage(const DisplayMesh& mesh);

}  // namespace tangent::view
