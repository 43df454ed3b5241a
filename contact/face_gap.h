#pragma once

// Two flat faces against each other (nurbs/flat.h; docs/contact.md, "Face contacts"). Where two
// flat faces meet, their extremal pair is a continuum (parallel faces) or lies at a corner of one
// (tilted): no interior extremum holds them. The height of a face's points above the other's
// plane is affine along the face, so over the part of a face that lies over the other it is least
// at a corner of that part: a corner of either face lying over the other, or where their edges
// cross. This measures the corners: each corner of f against g and each corner of g against f,
// the signed distance along the other's normal at its closest point, taken when that point is
// inside the other's domain (the corner lies over the face). Edge crossings (a face overhanging
// the other's edge) are not measured.

#include <Eigen/Core>

#include "contact/placed.h"
#include "nurbs/flat.h"
#include "nurbs/surface.h"

namespace tangent::contact {

struct FaceCorner {
  bool found = false;  ///< some corner lies over the other face
  bool of_f = true;    ///< the corner is f's (else g's)
  int corner = 0;      ///< its index in its face's FlatQuad
  /// Parameters in the pair's order (f's, then g's), the distance along the other face's
  /// outward normal (> 0: apart), and the two points (world).
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  double beta = 0.0;
  Eigen::Vector3d p_f = Eigen::Vector3d::Zero(), p_g = Eigen::Vector3d::Zero();
};

/// The corner of f or g lying over the other face nearest to it (smallest β). Allocation free.
FaceCorner LowestCorner(const nurbs::NurbsSurface& f, const nurbs::FlatQuad& qf, const BodyPose& pf,
                        const nurbs::NurbsSurface& g, const nurbs::FlatQuad& qg,
                        const BodyPose& pg);

}  // namespace tangent::contact
