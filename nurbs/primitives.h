#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "nurbs/curve.h"
#include "nurbs/surface.h"

namespace tangent::nurbs {

/// Exact NURBS forms of the shapes scenes are built from. All lengths in metres, all surfaces
/// in their own frame; outward normals are S_u × S_v unless stated otherwise. Quadrics are exact
/// rational quadratics (circles as nine-point, four-arc rational quadratics).

/// Bilinear plane patch S(u,v) = origin + u·edge_u + v·edge_v on [0,1]².
NurbsSurface MakePlanePatch(const Eigen::Vector3d& origin, const Eigen::Vector3d& edge_u,
                            const Eigen::Vector3d& edge_v);

/// Sphere of `radius` about `center`: u ∈ [0,1] is longitude (full turn about +z), v ∈ [0,1]
/// latitude from the south pole (v = 0) to the north pole (v = 1). At the poles a whole row of
/// control points collapses to one point, so S_u = 0 there (a degenerate parameterization).
/// Normal S_u × S_v points outward.
NurbsSurface MakeSphere(const Eigen::Vector3d& center, double radius);

/// Cylinder of `radius` about +z from z = 0 to z = height: u ∈ [0,1] around, v ∈ [0,1] along.
NurbsSurface MakeCylinder(double radius, double height);

/// Cone about +z with its apex at the origin and its base circle of `radius` at z = height:
/// u ∈ [0,1] around, v ∈ [0,1] from the apex (a pole row: S_u = 0 at v = 0, where the surface
/// has a vertex, not a tangent plane) to the base.
NurbsSurface MakeCone(double radius, double height);

/// Barrel about +z from z = 0 to z = height: the profile a circular arc of radius `crown` (the
/// crown radius, > height / 2) whose widest point, `radius` from the axis, is at mid-height; the
/// ends are radius − crown + √(crown² − height²/4) from the axis. u ∈ [0,1] around, v ∈ [0,1]
/// along; the normal points outward. A crowned peg: against a hole's wall it touches at a point
/// where a cylinder would touch along a line.
NurbsSurface MakeBarrel(double radius, double height, double crown);

/// Torus about +z: tube of radius `minor` around a circle of radius `major` in z = 0.
/// u ∈ [0,1] around the axis, v ∈ [0,1] around the tube. @pre 0 < minor < major.
NurbsSurface MakeTorus(double major, double minor);

/// One piece of a planar path drawn like a turtle in the z = 0 plane: a straight line of
/// `length`, or a circular arc of `radius` turning by `angle` (radians; > 0 turns left).
struct PathSegment {
  enum class Kind { kLine, kArc } kind;
  double length_or_radius;
  double angle;
  static PathSegment Line(double length) { return {Kind::kLine, length, 0.0}; }
  static PathSegment Arc(double radius, double angle) { return {Kind::kArc, radius, angle}; }
};

/// A tube (pipe) of radius `radius` swept along a G¹ planar path that starts at `start`
/// heading along `heading` (unit, in z = 0). Exact: each line piece is a cylinder piece and each
/// arc piece (split into ≤ 90° parts) a torus piece, joined with double knots. u ∈ [0,1] runs
/// along the path (proportional to arc length), v ∈ [0,1] around the wire. @pre radius is less
/// than every arc radius. @throws std::invalid_argument otherwise.
NurbsSurface MakeTube(const std::vector<PathSegment>& path, double radius,
                      const Eigen::Vector2d& start = Eigen::Vector2d::Zero(),
                      const Eigen::Vector2d& heading = Eigen::Vector2d::UnitY());

/// Centre line of a standard (Gem) paperclip, about 33 mm long and 8.9 mm wide over the wire,
/// for wire of 0.9 mm diameter: four straight legs joined by three 180° bends; the inner loop's
/// legs run 1.5 mm (centre to centre) from the outer loop's. Starts at the origin heading +y.
std::vector<PathSegment> PaperclipPath();
/// Wire radius of a standard paperclip: 0.45 mm.
inline constexpr double kPaperclipWireRadius = 0.45e-3;

/// Bicubic graph over the rectangle [x0, x0+lx] × [y0, y0+ly]: heights[i][j] are control-point
/// heights on an nx × ny net (clamped uniform knots), placed at the Greville abscissae so that
/// x and y are exactly linear in u and v (S = (x0 + u·lx, y0 + v·ly, f(u,v))). @pre nx, ny ≥ 4.
NurbsSurface MakeHeightGridPatch(double x0, double y0, double lx, double ly,
                                 const std::vector<std::vector<double>>& heights);

/// A strongly non-orthogonal bicubic patch: the net is sheared so the u and v directions meet
/// at `angle` (radians; the contact-Jacobian hard case wants 10°–20°), with a smooth bump of
/// height `bump` (metres) and, when `rational`, weights varying in [0.95, 1.05]. Size `size`
/// along both parameter directions; 5 x 5 control points, one interior knot each way.
NurbsSurface MakeShearedPatch(double angle, double size, double bump, bool rational);

/// Parameter-domain curves for trimming loops (trim.h): the exact rational quadratic circle
/// (9 control points, t ∈ [0, 1] from angle 0, counter-clockwise unless `clockwise`), and a
/// polyline as one degree-1 curve (its vertices at the integer parameters, C⁰ knots).
NurbsCurve2d MakeCircle2d(const Eigen::Vector2d& center, double radius, bool clockwise = false);
NurbsCurve2d MakePolyline2d(const std::vector<Eigen::Vector2d>& points);

/// The surface moved rigidly by X (points x ↦ X x): NURBS are invariant under affine maps of
/// their control points, so this is exact (the weights stay). For placing primitives on bodies.
NurbsSurface Transformed(const NurbsSurface& surface, const Eigen::Isometry3d& X);

/// The same surface with u running the other way, S'(u, v) = S(a + b − u, v) on the same
/// domain [a, b]: its normal S'_u × S'_v points to the other side (a hole's wall as a cylinder
/// facing its axis).
NurbsSurface ReversedU(const NurbsSurface& surface);

}  // namespace tangent::nurbs
