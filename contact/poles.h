#pragma once

// Poles of a parameterization, for the extremal solvers (internal header).
//
// At a pole row (a domain edge the parameterization collapses to a point, S_u = 0 along it) the
// surface is smooth but Newton's matrix is singular: the angle parameter moves nothing there,
// and a minimization reaching the pole can stop on it with the angle wherever the seed left it.
// The pole is handled as the point it is: which way the surface leaves it is chosen by the
// angle (the departure t(a) = ±∂S/∂across at the pole row), so from a pole either some departure
// decreases the distance (the minimum is near the pole: restart just off it, along the best
// departure) or none does (the pole is the extremum: d lies along the limit normal).

#include <Eigen/Core>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::contact::internal {

/// What a solver does at a pole its iterate reached: nothing (no pole), restart just off it
/// (some departure decreases the distance), or answer the pole itself (it is the extremum).
enum class PoleAction { kNone, kEscape, kExtremum };

/// A pole row at or within `fraction` (1e-3 by default) of the domain from uv: the parameter
/// across it (1: the row v = bound, where S_u vanishes; 0: u = bound, where S_v vanishes), the
/// bound, the inward sign.
struct PoleRow {
  bool found = false;
  int across = 1;
  double bound = 0.0;
  double inward = 1.0;
};
PoleRow FindPoleRow(const nurbs::NurbsSurface& s, const Eigen::Vector2d& uv,
                    double fraction = 1e-3);

/// Whether the domain edge where parameter `across` is held at `bound` collapses to a point
/// there, measured at uv's other parameter: the derivative along the row vanishes
/// (|along| ≤ kDegenerateRatio |across|).
bool IsPoleRowAt(const nurbs::NurbsSurface& s, int across, double bound, const Eigen::Vector2d& uv);

/// A seed just off the pole row (1e-3 of the across parameter's domain width inward), leaving
/// it at angle parameter `angle`: where a minimization restarts from a pole.
Eigen::Vector2d OffPole(const nurbs::NurbsSurface& s, const PoleRow& row, double angle);

/// The departure from the pole row of a placed surface that most decreases ½|d|², where moving
/// the surface's point by δp changes d by sign·δp: its slope per unit length (< 0: a descent),
/// and the angle parameter it leaves at.
double BestDeparture(const nurbs::NurbsSurface& s, const BodyPose& pose, const PoleRow& row,
                     const Eigen::Vector3d& d, double sign, double* angle);

/// Whether the pole point is a minimum of the distance to `other` over its neighbourhood on the
/// surface (the second-order test: the first order vanishes at a pole). When it is not,
/// *descent_angle (optional) gets the angle parameter of the departure that lowers it most: at
/// a pole that is the distance's maximum or a saddle (the far pole of a sphere over a plane)
/// the first-order test finds no descent, and the minimization leaves along this one.
bool PoleIsMinimum(const nurbs::NurbsSurface& s, const BodyPose& pose, const PoleRow& row,
                   const Eigen::Vector3d& other, double* descent_angle = nullptr);

/// Whether the pole row is a vertex (a cone's apex, a revolved profile meeting its axis at an
/// angle): the limit normal depends on the direction the surface leaves the pole in, so the
/// surface has no tangent plane there. At a smooth pole (a sphere's) it is one normal. Measured
/// at three angles: a vertex when two limit normals differ by more than 1e-6.
bool IsVertex(const nurbs::NurbsSurface& s, const PoleRow& row);

}  // namespace tangent::contact::internal
