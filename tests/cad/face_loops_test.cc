// A face's loops within the file's tolerance (cad/face_loops.h, issue 37): Open CASCADE faces whose
// pcurves are changed the ways real files carry them, repaired where the part moves by no more
// than the edge's or vertex's tolerance in space, refused with the amount where it would move
// more. Parameters here are 0.1 m per unit, so every distance in space is a tenth of the
// parameter's.

#include "cad/face_loops.h"

#include <gtest/gtest.h>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace tangent::cad {
namespace {

// A degree-1 B-spline surface through a grid of points (rows along u), parameters [0, 1]².
Handle(Geom_BSplineSurface) Bilinear(const std::vector<std::vector<gp_Pnt>>& rows) {
  const int nu = static_cast<int>(rows.size()), nv = static_cast<int>(rows[0].size());
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) poles(i + 1, j + 1) = rows[i][j];
  }
  auto knots = [](int n, TColStd_Array1OfReal* k, TColStd_Array1OfInteger* m) {
    k->Resize(1, n, false);
    m->Resize(1, n, false);
    for (int i = 1; i <= n; ++i) {
      k->SetValue(i, (i - 1.0) / (n - 1.0));
      m->SetValue(i, i == 1 || i == n ? 2 : 1);
    }
  };
  TColStd_Array1OfReal ku(1, 1), kv(1, 1);
  TColStd_Array1OfInteger mu(1, 1), mv(1, 1);
  knots(nu, &ku, &mu);
  knots(nv, &kv, &mv);
  return new Geom_BSplineSurface(poles, ku, kv, mu, mv, 1, 1);
}

// Ours, from the same poles and knots.
nurbs::NurbsSurface Ours(const Handle(Geom_BSplineSurface) & bs) {
  TColStd_Array1OfReal ku(1, bs->NbUPoles() + 2), kv(1, bs->NbVPoles() + 2);
  bs->UKnotSequence(ku);
  bs->VKnotSequence(kv);
  std::vector<Eigen::Vector3d> points;
  for (int i = 1; i <= bs->NbUPoles(); ++i) {
    for (int j = 1; j <= bs->NbVPoles(); ++j) {
      const gp_Pnt p = bs->Pole(i, j);
      points.emplace_back(p.X(), p.Y(), p.Z());
    }
  }
  return nurbs::NurbsSurface(nurbs::KnotVector(1, std::vector<double>(ku.begin(), ku.end())),
                             nurbs::KnotVector(1, std::vector<double>(kv.begin(), kv.end())),
                             points);
}

// The straight pcurve from a to b over the parameters [first, last].
Handle(Geom2d_Curve) Segment(gp_Pnt2d a, gp_Pnt2d b, double first, double last) {
  TColgp_Array1OfPnt2d poles(1, 2);
  poles(1) = a;
  poles(2) = b;
  TColStd_Array1OfReal knots(1, 2);
  knots(1) = first;
  knots(2) = last;
  TColStd_Array1OfInteger mults(1, 2);
  mults(1) = mults(2) = 2;
  return new Geom2d_BSplineCurve(poles, knots, mults, 1);
}

// The pcurve of an edge made from the old one's end points (in its direction).
using Change = std::function<std::pair<gp_Pnt2d, gp_Pnt2d>(gp_Pnt2d, gp_Pnt2d)>;

// The face over the whole surface, with the edge whose pcurve runs between `from` and `to` given
// the straight pcurve change(start, end) instead, and the tolerance `tolerance`.
TopoDS_Face Changed(const Handle(Geom_BSplineSurface) & bs, gp_Pnt2d from, gp_Pnt2d to,
                    const Change& change, double tolerance) {
  TopoDS_Face face = BRepBuilderAPI_MakeFace(bs, 1e-7).Face();
  bool found = false;
  for (TopExp_Explorer x(face, TopAbs_EDGE); x.More(); x.Next()) {
    const TopoDS_Edge edge = TopoDS::Edge(x.Current());
    double first, last;
    const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, first, last);
    const gp_Pnt2d a = pc->Value(first), b = pc->Value(last);
    const bool same = a.Distance(from) < 1e-12 && b.Distance(to) < 1e-12;
    const bool swapped = a.Distance(to) < 1e-12 && b.Distance(from) < 1e-12;
    if (!same && !swapped) continue;
    BRep_Builder builder;
    const auto [start, end] = change(a, b);
    builder.UpdateEdge(edge, Segment(start, end, first, last), face, tolerance);
    found = true;
    break;
  }
  EXPECT_TRUE(found) << "no edge from (" << from.X() << ", " << from.Y() << ")";
  return face;
}

// A 0.1 m square, flat.
Handle(Geom_BSplineSurface) Square() {
  return Bilinear({{gp_Pnt(0, 0, 0), gp_Pnt(0, 0.1, 0)}, {gp_Pnt(0.1, 0, 0), gp_Pnt(0.1, 0.1, 0)}});
}

std::string Refusal(const TopoDS_Face& face, const Handle(Geom_BSplineSurface) & bs) {
  try {
    BuildFaceLoops(face, bs, false, Ours(bs));
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(FaceLoopsTest, APcurvePastTheDomainIsClampedWithinItsEdgesTolerance) {
  const Handle(Geom_BSplineSurface) bs = Square();
  // The edge along v = 0 given 1e-6 below it (1e-7 m), with a tolerance of 1e-6 m.
  auto below = [](double by) -> Change {
    return [by](gp_Pnt2d a, gp_Pnt2d b) {
      return std::pair(gp_Pnt2d(a.X(), a.Y() - by), gp_Pnt2d(b.X(), b.Y() - by));
    };
  };
  const FaceLoops loops =
      BuildFaceLoops(Changed(bs, {0, 0}, {1, 0}, below(1e-6), 1e-6), bs, false, Ours(bs));
  EXPECT_EQ(loops.repairs.clamped, 1);
  EXPECT_NEAR(loops.repairs.clamped_by, 1e-7, 1e-15);
  ASSERT_TRUE(loops.outer.has_value());
  for (const nurbs::NurbsCurve2d& c : loops.outer->curves) {
    for (const auto& h : c.weighted_points()) EXPECT_GE(h[1] / h[2], 0.0);
  }
  EXPECT_EQ(loops.repairs.Describe(), "1 pcurve clamped into the domain (by up to 1e-07 m)");
  // 1e-4 below (1e-5 m in space): beyond the tolerance, refused with both amounts.
  EXPECT_EQ(Refusal(Changed(bs, {0, 0}, {1, 0}, below(1e-4), 1e-6), bs),
            "an edge's pcurve leaves the surface's domain by 0.0001 in the face's parameters, "
            "1e-05 m in space, beyond the edge's tolerance 1e-06 m");
}

TEST(FaceLoopsTest, AGapWithinTheFilesToleranceIsClosedAndAWiderOneRefused) {
  const Handle(Geom_BSplineSurface) bs = Square();
  // The edge along v = 0 stopping 1e-5 short of its corner: 1e-6 m.
  const Change short_of = [](gp_Pnt2d a, gp_Pnt2d b) {
    return std::pair(a, gp_Pnt2d(b.X() + (a.X() - b.X()) * 1e-5, b.Y()));
  };
  const FaceLoops loops =
      BuildFaceLoops(Changed(bs, {0, 0}, {1, 0}, short_of, 2e-6), bs, false, Ours(bs));
  EXPECT_EQ(loops.repairs.gaps, 1);
  EXPECT_NEAR(loops.repairs.gaps_by, 1e-6, 1e-15);
  EXPECT_EQ(loops.repairs.joined, 0);
  std::vector<std::string> warnings;
  const nurbs::TrimmedDomain trim({0, 0}, {1, 1}, loops.outer, loops.holes, {}, &warnings);
  EXPECT_TRUE(trim.Contains({0.5, 0.5}));
  EXPECT_EQ(Refusal(Changed(bs, {0, 0}, {1, 0}, short_of, 1e-7), bs),
            "a wire's pcurves leave a gap of 1e-05 in the face's parameters, 1e-06 m in space, "
            "beyond the file's tolerance 1e-07 m there");
}

TEST(FaceLoopsTest, EndsApartInTheParametersButTogetherInSpaceAreJoined) {
  // A triangle: the edge v = 1 collapsed to the point (0.05, 0.1, 0). Its (degenerate) edge's
  // pcurve runs only half way, 0.5 apart from the next edge in the parameters, 0 m in space.
  const Handle(Geom_BSplineSurface) bs = Bilinear(
      {{gp_Pnt(0, 0, 0), gp_Pnt(0.05, 0.1, 0)}, {gp_Pnt(0.1, 0, 0), gp_Pnt(0.05, 0.1, 0)}});
  const Change half = [](gp_Pnt2d a, gp_Pnt2d b) {
    return std::pair(a, gp_Pnt2d(0.5 * (a.X() + b.X()), b.Y()));
  };
  const FaceLoops loops =
      BuildFaceLoops(Changed(bs, {1, 1}, {0, 1}, half, 1e-7), bs, false, Ours(bs));
  EXPECT_EQ(loops.repairs.gaps, 1);
  EXPECT_EQ(loops.repairs.joined, 1);
  EXPECT_LT(loops.repairs.gaps_by, 1e-15);
  ASSERT_TRUE(loops.outer.has_value());
  EXPECT_EQ(loops.outer->curves.size(), 5u);  // the four edges and the piece that joins them
}

TEST(FaceLoopsTest, APcurveGivenOnePeriodAwayIsMovedBack) {
  // A square tube (closed in u: its first and last rows of poles are the same points), 0.1 m
  // long in v. The edge along v = 0 given one period over, u from 1 to 2.
  const Handle(Geom_BSplineSurface) bs = Bilinear({{gp_Pnt(0, 0, 0), gp_Pnt(0, 0, 0.1)},
                                                   {gp_Pnt(0.1, 0, 0), gp_Pnt(0.1, 0, 0.1)},
                                                   {gp_Pnt(0.1, 0.1, 0), gp_Pnt(0.1, 0.1, 0.1)},
                                                   {gp_Pnt(0, 0.1, 0), gp_Pnt(0, 0.1, 0.1)},
                                                   {gp_Pnt(0, 0, 0), gp_Pnt(0, 0, 0.1)}});
  const Change over = [](gp_Pnt2d a, gp_Pnt2d b) {
    return std::pair(gp_Pnt2d(a.X() + 1, a.Y()), gp_Pnt2d(b.X() + 1, b.Y()));
  };
  const FaceLoops loops =
      BuildFaceLoops(Changed(bs, {0, 0}, {1, 0}, over, 1e-7), bs, false, Ours(bs));
  EXPECT_EQ(loops.repairs.shifted, 1);
  EXPECT_EQ(loops.repairs.clamped, 0);
  std::vector<std::string> warnings;
  const nurbs::TrimmedDomain trim({0, 0}, {1, 1}, loops.outer, loops.holes, {}, &warnings);
  EXPECT_TRUE(trim.Contains({0.5, 0.5}));
  // On a surface that is not closed the same pcurve is refused.
  EXPECT_NE(Refusal(Changed(Square(), {0, 0}, {1, 0}, over, 1e-7), Square())
                .find("leaves the surface's domain by 1 in the face's parameters"),
            std::string::npos);
}

}  // namespace
}  // namespace tangent::cad
