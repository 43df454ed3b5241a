#pragma once

// Flat quadrilateral faces (docs/contact.md, "Face contacts"): a surface whose control points
// all lie on one plane, and whose four boundary rows of control points each lie on one line.
// Such a surface lies in its control points' plane (the convex hull property) and is bounded by
// the four straight segments between its corners, so its image is the quadrilateral of its
// corners and any affine function over it, such as the height above another plane, is least at
// a corner. A box's faces and plane patches are such faces.

#include <array>
#include <optional>

#include <Eigen/Core>

#include "nurbs/surface.h"

namespace tangent::nurbs {

struct FlatQuad {
  /// The domain's corners in order round it: (u₀, v₀), (u₁, v₀), (u₁, v₁), (u₀, v₁).
  std::array<Eigen::Vector2d, 4> corners;
  /// The corners' points, surface frame.
  std::array<Eigen::Vector3d, 4> points;
  /// The domain's middle (where a closest point on the face is first sought).
  Eigen::Vector2d middle;
};

/// The face's corners when `s` is flat with straight edges to `tolerance` times the size of its
/// control net (its box's diagonal); nothing otherwise (a curved surface, a curved edge, a
/// periodic surface, a collapsed edge).
std::optional<FlatQuad> FlatQuadOf(const NurbsSurface& s, double tolerance = 1e-9);

}  // namespace tangent::nurbs
