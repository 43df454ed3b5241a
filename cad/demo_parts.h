#pragma once
// The imported-parts demo's two parts (scenes/peg_in_hole_cad.json), built by Open CASCADE the
// way a designer's CAD system would build them, in millimetres: the peg-in-hole scene's plate
// and peg as solids, not as the scene file's primitives.
//
//  - PegPlate: a 40 x 40 x 15 block, top face at z = 0, with a blind hole 10 across and 10 deep
//    on the z axis (a cut by a cylinder): the top face is a plane trimmed by the hole's circle,
//    the wall a cylinder with a seam, the floor a disc.
//  - Peg: a barrel 8 long, 8 across at its middle (crown radius 20), on a shank 0.4 thinner up to
//    z = 30 (a revolved profile), and a spherical end below z = 0 whose axis is turned 45° off
//    the peg's (a sphere cut at z = 0, fused on): a revolved end would have its pole on the axis,
//    at the point that touches the plate when the peg stands upright.
//
// Header only; for cad/'s generator and the tests (Open CASCADE stays out of the core).

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <TopoDS_Shape.hxx>
#include <gp.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt.hxx>

#include <cmath>

namespace tangent::cad::demo {

inline TopoDS_Shape PegPlate() {
  const TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(-20, -20, -15), 40.0, 40.0, 15.0).Shape();
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -10), gp::DZ()), 5.0, 11.0).Shape();
  return BRepAlgoAPI_Cut(block, hole).Shape();
}

inline TopoDS_Shape Peg() {
  const double crown = 20.0, middle = 4.0, half = 4.0;
  const double end = middle - (crown - std::sqrt(crown * crown - half * half));  // 3.595917942
  // The profile in the xz plane: axis, top, shank, the crown's arc (centre across the axis),
  // the bottom edge back to the axis; revolved a full turn about z.
  const gp_Pnt axis_top(0, 0, 30), shank_top(end, 0, 30), shank_bottom(end, 0, 2 * half),
      crown_mid(middle, 0, half), crown_bottom(end, 0, 0), axis_bottom(0, 0, 0);
  BRepBuilderAPI_MakeWire wire;
  wire.Add(BRepBuilderAPI_MakeEdge(axis_top, shank_top).Edge());
  wire.Add(BRepBuilderAPI_MakeEdge(shank_top, shank_bottom).Edge());
  wire.Add(
      BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(shank_bottom, crown_mid, crown_bottom).Value())
          .Edge());
  wire.Add(BRepBuilderAPI_MakeEdge(crown_bottom, axis_bottom).Edge());
  wire.Add(BRepBuilderAPI_MakeEdge(axis_bottom, axis_top).Edge());
  const TopoDS_Face profile = BRepBuilderAPI_MakeFace(wire.Wire()).Face();
  const TopoDS_Shape body =
      BRepPrimAPI_MakeRevol(profile, gp_Ax1(gp_Pnt(0, 0, 0), gp::DZ()), 2 * M_PI).Shape();
  // The end: a sphere whose poles are 45° off the peg's axis, its part below z = 0.
  const gp_Dir tilted(0.0, std::sin(M_PI / 4), std::cos(M_PI / 4));
  const TopoDS_Shape sphere = BRepPrimAPI_MakeSphere(gp_Ax2(gp_Pnt(0, 0, 0), tilted), end).Shape();
  const TopoDS_Shape above =
      BRepPrimAPI_MakeBox(gp_Pnt(-2 * end, -2 * end, 0), 4 * end, 4 * end, 2 * end).Shape();
  const TopoDS_Shape cap = BRepAlgoAPI_Cut(sphere, above).Shape();
  return BRepAlgoAPI_Fuse(body, cap).Shape();
}

}  // namespace tangent::cad::demo
