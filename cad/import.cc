// Open CASCADE → Tangent (import.h). Read, heal, convert each face to a B-spline with its
// pcurves, and hand the result to nurbs:: (surfaces) and nurbs::TrimmedDomain (loops).

#include "cad/import.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESControl_Controller.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Controller.hxx>
#include <ShapeBuild_ReShape.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include <nlohmann/json.hpp>

#include "cad/deviation.h"
#include "cad/face_loops.h"
#include "nurbs/json_io.h"

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

// A file read into an XCAF document: the shape (its free shapes together), and the document's
// names and colours for its solids and faces.
struct ReadPart {
  TopoDS_Shape shape;
  Handle(TDocStd_Document) doc;
  Handle(XCAFDoc_ShapeTool) shapes;
  Handle(XCAFDoc_ColorTool) colours;

  /// The name the file gives `s` (its own label's, else its instance's referred shape's): empty
  /// when it has none.
  std::string NameOf(const TopoDS_Shape& s) const {
    TDF_Label label;
    if (shapes.IsNull() || !shapes->Search(s, label, true, true, true)) return "";
    Handle(TDataStd_Name) name;
    TDF_Label referred;
    if (!label.FindAttribute(TDataStd_Name::GetID(), name) &&
        XCAFDoc_ShapeTool::GetReferredShape(label, referred)) {
      referred.FindAttribute(TDataStd_Name::GetID(), name);
    }
    return name.IsNull() ? "" : TCollection_AsciiString(name->Get()).ToCString();
  }
  /// The surface colour the file gives `s` (sRGB, 0..1), else its generic colour.
  std::optional<std::array<double, 3>> ColourOf(const TopoDS_Shape& s) const {
    Quantity_Color c;
    if (colours.IsNull() || !(colours->GetColor(s, XCAFDoc_ColorSurf, c) ||
                              colours->GetColor(s, XCAFDoc_ColorGen, c))) {
      return std::nullopt;
    }
    std::array<double, 3> rgb{};
    c.Values(rgb[0], rgb[1], rgb[2], Quantity_TOC_sRGB);
    return rgb;
  }
};

ReadPart Read(const std::string& path) {
  if (!std::filesystem::exists(path)) throw ImportError(path + ": no such file");
  {
    std::ifstream in(path);
    if (!in) throw ImportError(path + ": cannot open the file");
    if (in.peek() == std::ifstream::traits_type::eof())
      throw ImportError(path + ": the file is empty");
  }
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  const bool step = ext == ".step" || ext == ".stp", iges = ext == ".igs" || ext == ".iges";
  if (!step && !iges) {
    throw ImportError(path + ": unknown extension \"" + ext +
                      "\" (STEP: .step, .stp; IGES: .igs, .iges)");
  }
  // Open CASCADE's readers print to stdout through its default messenger: errors only.
  for (const Handle(Message_Printer) & printer : Message::DefaultMessenger()->Printers()) {
    printer->SetTraceLevel(Message_Fail);
  }
  // Lengths in metres, whatever the file's unit: Open CASCADE's unit for the shapes it makes
  // (a process-wide setting, restored when the read is done: writers read it too). The
  // translators' parameters exist only once their controllers are initialized: in a fresh
  // process (tangent-import, tangentd) setting the unit before that did nothing, and parts came
  // out with millimetre numbers taken as metres (the tests' processes had initialized them by
  // writing their fixtures first).
  STEPControl_Controller::Init();
  IGESControl_Controller::Init();
  struct Unit {
    std::string saved = Interface_Static::CVal("xstep.cascade.unit");
    Unit() {
      if (!Interface_Static::SetCVal("xstep.cascade.unit", "M")) {
        throw ImportError("Open CASCADE has no xstep.cascade.unit parameter to read in metres");
      }
    }
    ~Unit() { Interface_Static::SetCVal("xstep.cascade.unit", saved.c_str()); }
  } metres;
  // Through XCAF (the readers' document mode) so that the file's names and colours come along.
  ReadPart part;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", part.doc);
  const char* format = step ? "STEP" : "IGES";
  bool read = false, transferred = false;
  if (step) {
    STEPCAFControl_Reader reader;
    reader.SetNameMode(true);
    reader.SetColorMode(true);
    read = reader.ReadFile(path.c_str()) == IFSelect_RetDone;
    transferred = read && reader.Transfer(part.doc);
  } else {
    IGESCAFControl_Reader reader;
    reader.SetNameMode(true);
    reader.SetColorMode(true);
    read = reader.ReadFile(path.c_str()) == IFSelect_RetDone;
    transferred = read && reader.Transfer(part.doc);
  }
  if (!read) throw ImportError(path + ": not a readable " + format + " file");
  part.shapes = XCAFDoc_DocumentTool::ShapeTool(part.doc->Main());
  part.colours = XCAFDoc_DocumentTool::ColorTool(part.doc->Main());
  TDF_LabelSequence free;
  part.shapes->GetFreeShapes(free);
  if (!transferred || free.IsEmpty()) {
    throw ImportError(path + ": the " + format + " file holds no shape");
  }
  if (free.Length() == 1) {
    part.shape = XCAFDoc_ShapeTool::GetShape(free.Value(1));
  } else {
    TopoDS_Compound all;
    BRep_Builder builder;
    builder.MakeCompound(all);
    for (int i = 1; i <= free.Length(); ++i)
      builder.Add(all, XCAFDoc_ShapeTool::GetShape(free.Value(i)));
    part.shape = all;
  }
  return part;
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
  ImportedFace out{name, KindOf(face), ToSurface(bs, reversed), std::nullopt, 0.0, reversed,
                   "",   std::nullopt};
  const double u0 = out.surface.knots_u().domain_begin(), u1 = out.surface.knots_u().domain_end();
  const double v0 = out.surface.knots_v().domain_begin(), v1 = out.surface.knots_v().domain_end();

  // The loops, in the converted face's parameters, repaired within the file's tolerances.
  FaceLoops loops = BuildFaceLoops(nf, bs, reversed, out.surface);
  if (loops.repairs.any()) {
    warnings->push_back(name +
                        ": repaired within the file's tolerance: " + loops.repairs.Describe());
  }
  nurbs::TrimOptions trim_options;
  trim_options.band = options.trim_band;
  std::vector<std::string> trim_warnings;
  out.trim.emplace(Eigen::Vector2d(u0, v0), Eigen::Vector2d(u1, v1), std::move(loops.outer),
                   std::move(loops.holes), trim_options, &trim_warnings);
  for (const std::string& w : trim_warnings) warnings->push_back(name + ": " + w);

  // Deviation: against OCCT's evaluation of the converted surface at the same parameters, and
  // from the face's material to the file's own surface (FaceDeviation).
  const int n = options.deviation_grid;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = u0 + (u1 - u0) * i / n, v = v0 + (v1 - v0) * j / n;
      const Eigen::Vector3d ours = out.surface.Evaluate(u, v, 0).S;
      const gp_Pnt theirs = bs->Value(out.reversed ? u0 + u1 - u : u, v);
      out.deviation = std::max(out.deviation, gp_Pnt(ours[0], ours[1], ours[2]).Distance(theirs));
    }
  }
  out.deviation =
      std::max(out.deviation, FaceDeviation(out.surface, &*out.trim, BRep_Tool::Surface(face), n));
  return out;
}

// The part as JSON (surfaces and trims in nurbs/json_io's forms, doubles round-tripped exactly),
// for the isolated import's pipe.
nlohmann::json ToJson(const ImportedPart& part, const ImportOptions& options) {
  using nlohmann::json;
  auto colour = [](const std::optional<std::array<double, 3>>& c) {
    return c ? json(*c) : json(nullptr);
  };
  json bodies = json::array();
  for (const ImportedBody& b : part.bodies) {
    json faces = json::array();
    for (const ImportedFace& f : b.faces) {
      json face = {{"name", f.name},
                   {"kind", f.kind},
                   {"surface", nurbs::ToJson(f.surface)},
                   {"deviation", f.deviation},
                   {"reversed", f.reversed},
                   {"label", f.label},
                   {"colour", colour(f.colour)}};
      if (f.trim) {
        face["trim"] = nurbs::ToJson(*f.trim);
        face["trim"]["band"] = options.trim_band;
      }
      faces.push_back(std::move(face));
    }
    bodies.push_back(
        {{"name", b.name}, {"label", b.label}, {"colour", colour(b.colour)}, {"faces", faces}});
  }
  const ImportReport& r = part.report;
  return {{"bodies", bodies},
          {"report",
           {{"faces_by_kind", r.faces_by_kind},
            {"loops", r.loops},
            {"faces", r.faces},
            {"skipped", r.skipped},
            {"largest_deviation", r.largest_deviation},
            {"warnings", r.warnings}}}};
}

ImportedPart PartFromJson(const nlohmann::json& j, const std::string& path) {
  auto colour = [](const nlohmann::json& c) -> std::optional<std::array<double, 3>> {
    if (c.is_null()) return std::nullopt;
    return c.get<std::array<double, 3>>();
  };
  ImportedPart part;
  part.path = path;
  for (const auto& jb : j.at("bodies")) {
    ImportedBody b{jb.at("name"), jb.at("label"), colour(jb.at("colour")), {}};
    for (const auto& jf : jb.at("faces")) {
      ImportedFace f{
          jf.at("name"),  jf.at("kind"),          nurbs::SurfaceFromJson(jf.at("surface")),
          std::nullopt,   jf.at("deviation"),     jf.at("reversed"),
          jf.at("label"), colour(jf.at("colour"))};
      if (jf.contains("trim")) f.trim.emplace(nurbs::TrimFromJson(jf.at("trim"), f.surface));
      b.faces.push_back(std::move(f));
    }
    part.bodies.push_back(std::move(b));
  }
  const auto& r = j.at("report");
  part.report.faces_by_kind = r.at("faces_by_kind").get<std::vector<std::pair<std::string, int>>>();
  part.report.loops = r.at("loops");
  part.report.faces = r.at("faces");
  part.report.skipped = r.at("skipped");
  part.report.largest_deviation = r.at("largest_deviation");
  part.report.warnings = r.at("warnings").get<std::vector<std::string>>();
  return part;
}

ImportedPart ImportInProcess(const std::string& path, const ImportOptions& options) {
  ImportedPart part;
  part.path = path;
  ReadPart read;
  TopoDS_Shape shape;
  // The file's names and colours, found on the shapes as read (healing makes new ones): each
  // solid's or shell's and each coloured face's, keyed by the shape healing made of it.
  struct Found {
    TopoDS_Shape healed;
    std::string name;
    std::optional<std::array<double, 3>> colour;
  };
  std::vector<Found> found;
  try {
    read = Read(path);
    shape = read.shape;
    std::vector<std::pair<TopoDS_Shape, Found>> before;
    for (TopAbs_ShapeEnum kind : {TopAbs_SOLID, TopAbs_SHELL, TopAbs_FACE}) {
      for (TopExp_Explorer x(shape, kind); x.More(); x.Next()) {
        Found f{x.Current(), read.NameOf(x.Current()), read.ColourOf(x.Current())};
        if (!f.name.empty() || f.colour) before.emplace_back(x.Current(), f);
      }
    }
    if (options.heal) {
      ShapeFix_Shape fix(shape);
      fix.Perform();
      shape = fix.Shape();
      for (auto& [original, f] : before) f.healed = fix.Context()->Value(original);
    }
    for (auto& [original, f] : before) found.push_back(f);
  } catch (const Standard_Failure& e) {
    throw ImportError(path + ": Open CASCADE could not read it: " + e.GetMessageString());
  }
  if (shape.IsNull()) throw ImportError(path + ": the file holds no shape");
  auto lookup = [&found](const TopoDS_Shape& s) -> const Found* {
    for (const Found& f : found) {
      if (f.healed.IsSame(s)) return &f;
    }
    return nullptr;
  };
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
    ImportedBody b{name, "", std::nullopt, {}};
    if (const Found* f = lookup(body)) {
      b.label = f->name;
      b.colour = f->colour;
    }
    int k = 0;
    for (TopExp_Explorer x(body, TopAbs_FACE); x.More(); x.Next(), ++k) {
      const std::string face_name = name + " face " + std::to_string(k);
      try {
        ImportedFace f =
            ConvertFace(TopoDS::Face(x.Current()), face_name, options, &part.report.warnings);
        if (const Found* info = lookup(x.Current())) {
          f.label = info->name;
          f.colour = info->colour;
        }
        if (!f.colour) f.colour = b.colour;  // a face takes its body's colour
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

}  // namespace

ImportedPart ImportCad(const std::string& path, const ImportOptions& options) {
  if (!options.isolate) return ImportInProcess(path, options);
  int fds[2];
  if (pipe(fds) != 0) throw ImportError(path + ": cannot import: pipe: " + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw ImportError(path + ": cannot import: fork: " + std::strerror(errno));
  }
  if (pid == 0) {
    // The child: Open CASCADE reads and converts; the part (or the error) goes up the pipe as
    // "ok\n<json>" or "error\n<message>". Only _exit: no atexit handlers of the parent's. A
    // crash kills the child with its signal, whatever handlers the parent installed (a crash
    // reporter, a sanitizer, libFuzzer's): the parent reports it.
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) signal(sig, SIG_DFL);
    close(fds[0]);
    std::string out;
    try {
      out = "ok\n" + ToJson(ImportInProcess(path, options), options).dump();
    } catch (const ImportError& e) {
      out = std::string("error\n") + e.what();
    } catch (const std::exception& e) {
      out = "error\n" + path + ": " + e.what();
    }
    size_t done = 0;
    while (done < out.size()) {
      const ssize_t n = write(fds[1], out.data() + done, out.size() - done);
      if (n <= 0) _exit(2);
      done += static_cast<size_t>(n);
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string in;
  char buffer[1 << 16];
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(std::max(0.0, options.timeout_seconds));
  bool timed_out = false;
  for (;;) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    pollfd p{fds[0], POLLIN, 0};
    const int ready = left > 0.0 ? poll(&p, 1, static_cast<int>(std::ceil(left * 1e3))) : 0;
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      timed_out = true;
      break;
    }
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n > 0) {
      in.append(buffer, static_cast<size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    char text[64];
    std::snprintf(text, sizeof text, "%.3g", options.timeout_seconds);
    throw ImportError(path + ": the import took longer than " + text +
                      " s and was stopped (ImportOptions::timeout_seconds)");
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    throw ImportError(path + ": Open CASCADE crashed reading it (signal " + std::to_string(sig) +
                      ", " + strsignal(sig) + ")");
  }
  if (in.rfind("ok\n", 0) == 0) {
    try {
      return PartFromJson(nlohmann::json::parse(in.begin() + 3, in.end()), path);
    } catch (const std::exception& e) {
      throw ImportError(path + ": the import's result could not be read back: " + e.what());
    }
  }
  if (in.rfind("error\n", 0) == 0) throw ImportError(in.substr(6));
  throw ImportError(path + ": the import stopped without a result (exit status " +
                    std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
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
  auto describe = [](const std::string& label, const std::optional<std::array<double, 3>>& c) {
    std::string out;
    if (!label.empty()) out += " \"" + label + "\"";
    if (c) {
      char rgb[64];
      std::snprintf(rgb, sizeof rgb, " colour (%.3f, %.3f, %.3f)", (*c)[0], (*c)[1], (*c)[2]);
      out += rgb;
    }
    return out;
  };
  for (const ImportedBody& b : part.bodies) {
    const std::string about = describe(b.label, b.colour);
    if (!about.empty()) lines.push_back("  " + b.name + ":" + about);
    for (const ImportedFace& f : b.faces) {
      std::snprintf(text, sizeof text, "  %s: %s%s, %zu loop(s), deviation %.3g m", f.name.c_str(),
                    f.kind.c_str(), f.reversed ? " (reversed)" : "",
                    f.trim ? f.trim->loops().size() : 0, f.deviation);
      // A face's own label or colour (not the one it takes from its body).
      lines.emplace_back(text + describe(f.label, f.colour == b.colour ? std::nullopt : f.colour));
    }
  }
  for (const std::string& w : part.report.warnings) lines.push_back("warning: " + w);
  return lines;
}

}  // namespace tangent::cad
