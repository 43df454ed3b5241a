// Open CASCADE → Tangent (import.h). Read, heal, convert each face to a B-spline with its
// pcurves, and hand the result to nurbs:: (surfaces) and nurbs::TrimmedDomain (loops).

#include "cad/import.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

namespace tangent::cad {

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string KindOf(const TopoDS_Face& face) {
  switch (BRepAdaptor_Surface(face, false).GetType()) {
    case GeomAbs_Plane:
      return "plane";
    case GeomAbs_Cylinder:
      return "cylinder";
    case GeomAbs_Cone:
      return "cone";
    case GeomAbs_Sphere:
      return "sphere";
    case GeomAbs_Torus:
      return "torus";
    case GeomAbs_BezierSurface:
      return "bezier";
    case GeomAbs_BSplineSurface:
      return "b-spline";
    case GeomAbs_SurfaceOfRevolution:
      return "revolution";
    case GeomAbs_SurfaceOfExtrusion:
      return "extrusion";
    case GeomAbs_OffsetSurface:
      return "offset";
    default:
      return "other";
  }
}

// The flat knot sequence of an OCCT knot array with multiplicities.
std::vector<double> Flat(const TColStd_Array1OfReal& knots) {
  return std::vector<double>(knots.begin(), knots.end());
}

// Our surface from a non-periodic OCCT B-spline surface; `flip_u` reverses the u direction
// (u → u0 + u1 − u).
nurbs::NurbsSurface ToSurface(const Handle(Geom_BSplineSurface) & s, bool flip_u) {
  TColStd_Array1OfReal ku(1, s->NbUPoles() + s->UDegree() + 1);
  TColStd_Array1OfReal kv(1, s->NbVPoles() + s->VDegree() + 1);
  s->UKnotSequence(ku);
  s->VKnotSequence(kv);
  std::vector<double> knots_u = Flat(ku), knots_v = Flat(kv);
  const int nu = s->NbUPoles(), nv = s->NbVPoles();
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weights;
  const bool rational = s->IsURational() || s->IsVRational();
  for (int a = 0; a < nu; ++a) {
    const int i = flip_u ? nu - a : a + 1;
    for (int j = 1; j <= nv; ++j) {
      const gp_Pnt p = s->Pole(i, j);
      points.emplace_back(p.X(), p.Y(), p.Z());
      if (rational) weights.push_back(s->Weight(i, j));
    }
  }
  if (flip_u) {
    std::vector<double> k(knots_u.size());
    for (size_t i = 0; i < k.size(); ++i) {
      k[i] = knots_u.front() + knots_u.back() - knots_u[knots_u.size() - 1 - i];
    }
    knots_u = k;
  }
  return nurbs::NurbsSurface(nurbs::KnotVector(s->UDegree(), knots_u),
                             nurbs::KnotVector(s->VDegree(), knots_v), points, weights);
}

// A pcurve over [first, last] as our 2-D curve, reversed for a reversed edge, with u mirrored
// about the domain's middle when the face's u is flipped.
nurbs::NurbsCurve2d ToCurve(const Handle(Geom2d_Curve) & pc, double first, double last,
                            bool reversed, bool flip_u, double u_sum) {
  Handle(Geom2d_BSplineCurve) b =
      Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pc, first, last));
  if (b->IsPeriodic()) b->SetNotPeriodic();
  if (reversed) b->Reverse();
  TColStd_Array1OfReal k(1, b->NbPoles() + b->Degree() + 1);
  b->KnotSequence(k);
  std::vector<Eigen::Vector2d> points;
  std::vector<double> weights;
  for (int i = 1; i <= b->NbPoles(); ++i) {
    const gp_Pnt2d p = b->Pole(i);
    points.emplace_back(flip_u ? u_sum - p.X() : p.X(), p.Y());
    if (b->IsRational()) weights.push_back(b->Weight(i));
  }
  return nurbs::NurbsCurve2d(nurbs::KnotVector(b->Degree(), Flat(k)), points, weights);
}

// Closes the small gaps OCCT leaves between consecutive pcurves (within its edge tolerances):
// each pair of meeting end points moved to their middle. @return the largest gap.
double CloseLoop(std::vector<nurbs::NurbsCurve2d>* curves) {
  double largest = 0.0;
  const size_t n = curves->size();
  std::vector<std::vector<nurbs::NurbsCurve2d::HPoint>> cpw(n);
  for (size_t i = 0; i < n; ++i) cpw[i] = (*curves)[i].weighted_points();
  for (size_t i = 0; i < n; ++i) {
    auto& a = cpw[i].back();
    auto& b = cpw[(i + 1) % n].front();
    const Eigen::Vector2d pa = a.head<2>() / a[2], pb = b.head<2>() / b[2];
    largest = std::max(largest, (pa - pb).norm());
    const Eigen::Vector2d mid = 0.5 * (pa + pb);
    a.head<2>() = mid * a[2];
    b.head<2>() = mid * b[2];
  }
  for (size_t i = 0; i < n; ++i) {
    (*curves)[i] = nurbs::NurbsCurve2d::FromHomogeneous((*curves)[i].knots(), cpw[i]);
  }
  return largest;
}

TopoDS_Shape Read(const std::string& path) {
  if (!std::filesystem::exists(path)) throw ImportError(path + ": no such file");
  {
    std::ifstream in(path);
    if (!in) throw ImportError(path + ": cannot open the file");
    if (in.peek() == std::ifstream::traits_type::eof())
      throw ImportError(path + ": the file is empty");
  }
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  // Open CASCADE's readers print to stdout through its default messenger: errors only.
  for (const Handle(Message_Printer) & printer : Message::DefaultMessenger()->Printers()) {
    printer->SetTraceLevel(Message_Fail);
  }
  // Lengths in metres, whatever the file's unit: Open CASCADE's unit for the shapes it makes
  // (a process-wide setting, restored when the read is done: writers read it too).
  struct Unit {
    std::string saved = Interface_Static::CVal("xstep.cascade.unit");
    Unit() { Interface_Static::SetCVal("xstep.cascade.unit", "M"); }
    ~Unit() { Interface_Static::SetCVal("xstep.cascade.unit", saved.c_str()); }
  } metres;
  if (ext == ".step" || ext == ".stp") {
    STEPControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) {
      throw ImportError(path + ": not a readable STEP file");
    }
    if (reader.TransferRoots() == 0) throw ImportError(path + ": the STEP file holds no shape");
    return reader.OneShape();
  }
  if (ext == ".igs" || ext == ".iges") {
    IGESControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) {
      throw ImportError(path + ": not a readable IGES file");
    }
    if (reader.TransferRoots() == 0) throw ImportError(path + ": the IGES file holds no shape");
    return reader.OneShape();
  }
  throw ImportError(path + ": unknown extension \"" + ext +
                    "\" (STEP: .step, .stp; IGES: .igs, .iges)");
}

// One face: converted, its loops, its deviation. @throws std::exception (the caller skips it).
ImportedFace ConvertFace(const TopoDS_Face& face, const std::string& name,
                         const ImportOptions& options, std::vector<std::string>* warnings) {
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  BRepBuilderAPI_NurbsConvert convert(face, true);
  TopoDS_Face nf = TopoDS::Face(convert.Shape());
  {
    // The converted face's pcurves checked and remade where they do not follow its surface
    // (IGES cylinders came with a pcurve in another parameterization of v).
    ShapeFix_Face fix(nf);
    fix.Perform();
    nf = fix.Face();
  }
  Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(BRep_Tool::Surface(nf));
  if (bs.IsNull()) bs = GeomConvert::SurfaceToBSplineSurface(BRep_Tool::Surface(nf));
  if (bs->IsUPeriodic()) bs->SetUNotPeriodic();
  if (bs->IsVPeriodic()) bs->SetVNotPeriodic();
  ImportedFace out{name, KindOf(face), ToSurface(bs, reversed), std::nullopt, 0.0, reversed};
  const double u0 = out.surface.knots_u().domain_begin(), u1 = out.surface.knots_u().domain_end();
  const double v0 = out.surface.knots_v().domain_begin(), v1 = out.surface.knots_v().domain_end();

  // The loops, in the converted face's parameters.
  const TopoDS_Wire outer_wire = BRepTools::OuterWire(nf);
  std::optional<nurbs::TrimLoop> outer;
  std::vector<nurbs::TrimLoop> holes;
  const double diagonal = std::hypot(u1 - u0, v1 - v0);
  for (TopExp_Explorer w(nf, TopAbs_WIRE); w.More(); w.Next()) {
    const TopoDS_Wire wire = TopoDS::Wire(w.Current());
    // The wire's edges as stored, each pcurve in its edge's direction (and the other way
    // round), chained by their end points in the face's parameters: an edge whose end meets the
    // chain better than its start is taken reversed. (BRepTools_WireExplorer dropped an edge of
    // an IGES cylinder's seamed wire, and that wire's circles came with their orientation flags
    // opposite to their pcurves.) The loop's sense is TrimmedDomain's to check.
    std::vector<std::pair<nurbs::NurbsCurve2d, nurbs::NurbsCurve2d>> edges;  // (as is, reversed)
    for (TopExp_Explorer e(wire, TopAbs_EDGE); e.More(); e.Next()) {
      const TopoDS_Edge edge = TopoDS::Edge(e.Current());
      double first = 0.0, last = 0.0;
      const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, nf, first, last);
      if (pc.IsNull()) throw std::runtime_error("an edge has no curve on the face");
      const bool rev = edge.Orientation() == TopAbs_REVERSED;
      edges.emplace_back(ToCurve(pc, first, last, rev, out.reversed, u0 + u1),
                         ToCurve(pc, first, last, !rev, out.reversed, u0 + u1));
    }
    if (edges.empty()) continue;
    auto start = [](const nurbs::NurbsCurve2d& c) {
      return c.Evaluate(c.knots().domain_begin(), 0).C;
    };
    auto end = [](const nurbs::NurbsCurve2d& c) { return c.Evaluate(c.knots().domain_end(), 0).C; };
    nurbs::TrimLoop loop;
    std::vector<bool> used(edges.size(), false);
    loop.curves.push_back(edges[0].first);
    used[0] = true;
    for (size_t k = 1; k < edges.size(); ++k) {
      const Eigen::Vector2d at = end(loop.curves.back());
      size_t best = 0;
      bool flip = false;
      double best_gap = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < edges.size(); ++i) {
        if (used[i]) continue;
        const double forward = (start(edges[i].first) - at).norm();
        const double backward = (start(edges[i].second) - at).norm();
        if (forward < best_gap) best_gap = forward, best = i, flip = false;
        if (backward < best_gap) best_gap = backward, best = i, flip = true;
      }
      used[best] = true;
      loop.curves.push_back(flip ? edges[best].second : edges[best].first);
    }
    const double gap = CloseLoop(&loop.curves);
    if (gap > 1e-6 * diagonal) {
      throw std::runtime_error("a wire's pcurves leave a gap of " + std::to_string(gap) +
                               " in the face's parameters");
    }
    if (wire.IsSame(outer_wire)) {
      outer = std::move(loop);
    } else {
      holes.push_back(std::move(loop));
    }
  }
  nurbs::TrimOptions trim_options;
  trim_options.band = options.trim_band;
  std::vector<std::string> trim_warnings;
  out.trim.emplace(Eigen::Vector2d(u0, v0), Eigen::Vector2d(u1, v1), std::move(outer),
                   std::move(holes), trim_options, &trim_warnings);
  for (const std::string& w : trim_warnings) warnings->push_back(name + ": " + w);

  // Deviation: against OCCT's evaluation of the converted surface, and against the original
  // surface (the distance of our point to it).
  const Handle(Geom_Surface) original = BRep_Tool::Surface(face);
  const int n = options.deviation_grid;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = u0 + (u1 - u0) * i / n, v = v0 + (v1 - v0) * j / n;
      const Eigen::Vector3d ours = out.surface.Evaluate(u, v, 0).S;
      const gp_Pnt theirs = bs->Value(out.reversed ? u0 + u1 - u : u, v);
      const gp_Pnt p(ours[0], ours[1], ours[2]);
      out.deviation = std::max(out.deviation, p.Distance(theirs));
      GeomAPI_ProjectPointOnSurf projection(p, original);
      if (projection.NbPoints() > 0) {
        out.deviation = std::max(out.deviation, projection.LowerDistance());
      }
    }
  }
  return out;
}

}  // namespace

ImportedPart ImportCad(const std::string& path, const ImportOptions& options) {
  ImportedPart part;
  part.path = path;
  TopoDS_Shape shape;
  try {
    shape = Read(path);
    if (options.heal) {
      ShapeFix_Shape fix(shape);
      fix.Perform();
      shape = fix.Shape();
    }
  } catch (const Standard_Failure& e) {
    throw ImportError(path + ": Open CASCADE could not read it: " + e.GetMessageString());
  }
  if (shape.IsNull()) throw ImportError(path + ": the file holds no shape");
  // Bodies: the solids, else the shells, else the free faces together.
  std::vector<std::pair<std::string, TopoDS_Shape>> bodies;
  for (TopAbs_ShapeEnum kind : {TopAbs_SOLID, TopAbs_SHELL}) {
    for (TopExp_Explorer x(shape, kind); x.More(); x.Next()) {
      bodies.emplace_back(
          (kind == TopAbs_SOLID ? "solid " : "shell ") + std::to_string(bodies.size()),
          x.Current());
    }
    if (!bodies.empty()) break;
  }
  if (bodies.empty()) bodies.emplace_back("faces", shape);
  std::map<std::string, int> kinds;
  for (const auto& [name, body] : bodies) {
    ImportedBody b{name, {}};
    int k = 0;
    for (TopExp_Explorer x(body, TopAbs_FACE); x.More(); x.Next(), ++k) {
      const std::string face_name = name + " face " + std::to_string(k);
      try {
        ImportedFace f =
            ConvertFace(TopoDS::Face(x.Current()), face_name, options, &part.report.warnings);
        ++kinds[f.kind];
        part.report.loops += static_cast<int>(f.trim ? f.trim->loops().size() : 0);
        part.report.largest_deviation = std::max(part.report.largest_deviation, f.deviation);
        b.faces.push_back(std::move(f));
      } catch (const Standard_Failure& e) {
        ++part.report.skipped;
        part.report.warnings.push_back(face_name +
                                       ": skipped: Open CASCADE failed: " + e.GetMessageString());
      } catch (const std::exception& e) {
        ++part.report.skipped;
        part.report.warnings.push_back(face_name + ": skipped: " + e.what());
      }
    }
    part.report.faces += static_cast<int>(b.faces.size());
    if (!b.faces.empty()) part.bodies.push_back(std::move(b));
  }
  if (part.bodies.empty()) {
    std::string why = part.report.warnings.empty() ? "" : " (" + part.report.warnings[0] + ")";
    throw ImportError(path + ": no face could be imported" + why);
  }
  for (const auto& [kind, count] : kinds) part.report.faces_by_kind.emplace_back(kind, count);
  return part;
}

std::vector<std::string> ReportLines(const ImportedPart& part) {
  std::vector<std::string> lines;
  char text[256];
  std::snprintf(text, sizeof text, "%s: %zu bodies, %d faces, %d loops, %d skipped",
                part.path.c_str(), part.bodies.size(), part.report.faces, part.report.loops,
                part.report.skipped);
  lines.emplace_back(text);
  std::string kinds = "faces by surface:";
  for (const auto& [kind, count] : part.report.faces_by_kind) {
    kinds += " " + kind + " " + std::to_string(count);
  }
  lines.push_back(kinds);
  std::snprintf(text, sizeof text, "largest deviation from Open CASCADE: %.3g m",
                part.report.largest_deviation);
  lines.emplace_back(text);
  for (const ImportedBody& b : part.bodies) {
    for (const ImportedFace& f : b.faces) {
      std::snprintf(text, sizeof text, "  %s: %s%s, %zu loop(s), deviation %.3g m", f.name.c_str(),
                    f.kind.c_str(), f.reversed ? " (reversed)" : "",
                    f.trim ? f.trim->loops().size() : 0, f.deviation);
      lines.emplace_back(text);
    }
  }
  for (const std::string& w : part.report.warnings) lines.push_back("warning: " + w);
  return lines;
}

}  // namespace tangent::cad
