#pragma once

// Start points for a surface-pair minimization from the seed's neighbourhood (internal header;
// issue 38). A local descent from a seed ends at the minimum of the basin the seed lies in, and
// where the global minimum lies on a domain edge or corner its basin can be thin: a seed a few
// per cent of the domain away from it can lie in the basin of another minimum, a corner beyond
// a barrier. A boundary minimum is a minimum of a lower-dimensional problem (curve–surface along
// an edge, point–surface at a corner), so the edges and corners within the neighbourhood are
// sampled as such and their closest samples become further starts: the solver answers the
// nearest minimum reached from any of them. See docs/contact.md, "Boundary minima".

#include <Eigen/Core>
#include <array>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::contact::internal {

/// Samples per side of a neighbourhood window: 9 × 9 points on each surface, so a window of
/// ±10 % of the domain is sampled every 2.5 % of it.
inline constexpr int kWindowSamples = 8;

/// At most one start per domain edge of each surface (4 + 4).
struct NeighbourhoodStarts {
  std::array<Eigen::Vector4d, 8> u;
  int n = 0;
};

/// The starts of the neighbourhood of `seed`: each surface's window (the domain within ±radius
/// of each width around the seed's parameters) sampled on a (kWindowSamples+1)² grid; for each
/// domain edge the window reaches, the closest pair of its samples on that edge against the
/// other surface's window; none (and nothing sampled) when the windows reach no domain edge
/// (periodic seams and pole rows are not edges). Only boundary candidates: a nearer interior
/// minimum beside the seed is another basin's, which a cold seed's caller did not ask for.
/// Allocation free.
void FindNeighbourhoodStarts(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                             const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                             const Eigen::Vector4d& seed, double radius, NeighbourhoodStarts* out);

}  // namespace tangent::contact::internal
