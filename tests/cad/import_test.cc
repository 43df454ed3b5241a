// CAD import on fixtures written at test time by Open CASCADE from shapes it builds (a plate
// with holes, a filleted box, a trimmed cylinder, a revolved part with a seam, a B-spline face
// with short knot spans), exported to STEP and IGES in millimetres and read back: every face's
// geometry against Open CASCADE's evaluation, inside/outside against BRepClass_FaceClassifier
// on 10^4 random parameter points per face, lengths in metres; and bad files named.

#include "cad/import.h"

#include "cad/demo_parts.h"

#include "server/scene.h"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IGESCAFControl_Writer.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Shape.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Ax1.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt2d.hxx>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

namespace tangent::cad {
namespace {

using ::testing::HasSubstr;

std::string Dir() {
  const std::string d = std::filesystem::temp_directory_path() / "tangent_cad_fixtures";
  std::filesystem::create_directories(d);
  return d;
}

// The fixtures, in millimetres.
TopoDS_Shape PlateWithHoles() {
  TopoDS_Shape plate = BRepPrimAPI_MakeBox(100.0, 60.0, 8.0).Shape();
  for (const double x : {25.0, 70.0}) {
    const TopoDS_Shape hole =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, 30.0, -1.0), gp::DZ()), x < 50 ? 10.0 : 6.0, 10.0)
            .Shape();
    plate = BRepAlgoAPI_Cut(plate, hole).Shape();
  }
  return plate;
}

TopoDS_Shape FilletedBox() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape();
  BRepFilletAPI_MakeFillet fillet(box);
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(box, TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) fillet.Add(4.0, TopoDS::Edge(edges(i)));
  return fillet.Shape();
}

TopoDS_Shape TrimmedCylinder() {  // a 270° sector of a cylinder
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp::DZ()), 15.0, 30.0, 1.5 * M_PI)
      .Shape();
}

TopoDS_Shape RevolvedPart() {  // a stepped profile revolved a full turn: seams on every face
  BRepBuilderAPI_MakeWire wire;
  const gp_Pnt p[] = {{0, 0, 0}, {20, 0, 0}, {20, 0, 10}, {12, 0, 18}, {12, 0, 30}, {0, 0, 30}};
  for (int i = 0; i + 1 < 6; ++i) wire.Add(BRepBuilderAPI_MakeEdge(p[i], p[i + 1]).Edge());
  wire.Add(BRepBuilderAPI_MakeEdge(p[5], p[0]).Edge());
  const TopoDS_Face profile = BRepBuilderAPI_MakeFace(wire.Wire()).Face();
  return BRepPrimAPI_MakeRevol(profile, gp_Ax1(gp_Pnt(0, 0, 0), gp::DZ()), 2 * M_PI).Shape();
}

TopoDS_Shape ShortSpanFace() {  // a bicubic B-spline with a knot span of 1e-6 of its domain
  TColgp_Array2OfPnt poles(1, 5, 1, 4);
  for (int i = 1; i <= 5; ++i) {
    for (int j = 1; j <= 4; ++j) {
      poles(i, j) = gp_Pnt(10.0 * i, 10.0 * j, 3.0 * std::sin(i + 0.7 * j));
    }
  }
  TColStd_Array1OfReal uk(1, 3), vk(1, 2);
  TColStd_Array1OfInteger um(1, 3), vm(1, 2);
  uk(1) = 0.0, uk(2) = 0.5, uk(3) = 0.500001;  // then 1.0 below
  TColStd_Array1OfReal uk4(1, 4);
  TColStd_Array1OfInteger um4(1, 4);
  uk4(1) = 0.0, uk4(2) = 0.5, uk4(3) = 0.500001, uk4(4) = 1.0;
  um4(1) = 3, um4(2) = 1, um4(3) = 1, um4(4) = 3;  // degree 2 in u: 5 poles
  vk(1) = 0.0, vk(2) = 1.0;
  vm(1) = 4, vm(2) = 4;
  Handle(Geom_BSplineSurface) s = new Geom_BSplineSurface(poles, uk4, vk, um4, vm, 2, 3);
  return BRepBuilderAPI_MakeFace(s, 1e-7).Face();
}

std::string Write(const TopoDS_Shape& shape, const std::string& name, bool step,
                  const char* unit = "MM") {
  const std::string path = Dir() + "/" + name + (step ? ".step" : ".igs");
  // The shapes are built in millimetres (Open CASCADE's own unit), written in `unit`.
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  if (step) {
    STEPControl_Writer w;
    Interface_Static::SetCVal("write.step.unit", unit);
    EXPECT_EQ(w.Transfer(shape, STEPControl_AsIs), IFSelect_RetDone);
    EXPECT_EQ(w.Write(path.c_str()), IFSelect_RetDone);
  } else {
    IGESControl_Controller::Init();
    IGESControl_Writer w(unit, 1);  // BRep mode: faces with their loops
    EXPECT_TRUE(w.AddShape(shape));
    w.ComputeModel();
    EXPECT_TRUE(w.Write(path.c_str()));
  }
  return path;
}

// The faces of the file as Open CASCADE reads them (metres), in the importer's order, converted
// as the importer converts them.
std::vector<TopoDS_Face> TheirFaces(const std::string& path) {
  Interface_Static::SetCVal("xstep.cascade.unit", "M");
  TopoDS_Shape shape;
  if (path.ends_with(".step")) {
    STEPControl_Reader r;
    r.ReadFile(path.c_str());
    r.TransferRoots();
    shape = r.OneShape();
  } else {
    IGESControl_Reader r;
    r.ReadFile(path.c_str());
    r.TransferRoots();
    shape = r.OneShape();
  }
  ShapeFix_Shape fix(shape);
  fix.Perform();
  shape = fix.Shape();
  std::vector<TopoDS_Shape> bodies;
  for (TopAbs_ShapeEnum kind : {TopAbs_SOLID, TopAbs_SHELL}) {
    for (TopExp_Explorer x(shape, kind); x.More(); x.Next()) bodies.push_back(x.Current());
    if (!bodies.empty()) break;
  }
  if (bodies.empty()) bodies.push_back(shape);
  std::vector<TopoDS_Face> faces;
  for (const TopoDS_Shape& b : bodies) {
    for (TopExp_Explorer x(b, TopAbs_FACE); x.More(); x.Next()) {
      // Converted and its pcurves checked, as the importer does.
      ShapeFix_Face face_fix(TopoDS::Face(BRepBuilderAPI_NurbsConvert(x.Current(), true).Shape()));
      face_fix.Perform();
      face_fix.FixOrientation();
      faces.push_back(face_fix.Face());
    }
  }
  return faces;
}

struct Fixture {
  const char* name;
  std::function<TopoDS_Shape()> make;
};

class ImportTest : public ::testing::TestWithParam<std::tuple<int, bool>> {};

const Fixture kFixtures[] = {{"plate_with_holes", PlateWithHoles},
                             {"filleted_box", FilletedBox},
                             {"trimmed_cylinder", TrimmedCylinder},
                             {"revolved_part", RevolvedPart},
                             {"short_span_face", ShortSpanFace}};

TEST_P(ImportTest, FacesMatchOpenCascadeAndClassifyAsItsFaceClassifier) {
  const Fixture& fx = kFixtures[std::get<0>(GetParam())];
  const bool step = std::get<1>(GetParam());
  const TopoDS_Shape shape = fx.make();
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  const double size_mm = std::sqrt(box.SquareExtent());
  const std::string path = Write(shape, fx.name, step);
  const auto t0 = std::chrono::steady_clock::now();
  const ImportedPart part = ImportCad(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const std::string& line : ReportLines(part)) std::printf("%s\n", line.c_str());
  const std::vector<TopoDS_Face> theirs = TheirFaces(path);
  std::vector<const ImportedFace*> ours;
  for (const ImportedBody& b : part.bodies) {
    for (const ImportedFace& f : b.faces) ours.push_back(&f);
  }
  ASSERT_EQ(part.report.skipped, 0);
  ASSERT_EQ(ours.size(), theirs.size());
  const double size = 1e-3 * size_mm;  // metres: the file was in mm
  EXPECT_LT(part.report.largest_deviation, 1e-10 * size) << "part size " << size << " m";
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int disagreements = 0, checked = 0, on = 0, reference_wrong = 0;
  double xmin, ymin, zmin, xmax, ymax, zmax;
  box.Get(xmin, ymin, zmin, xmax, ymax, zmax);
  const Eigen::Vector3d part_lo = 1e-3 * Eigen::Vector3d(xmin, ymin, zmin);
  const Eigen::Vector3d part_hi = 1e-3 * Eigen::Vector3d(xmax, ymax, zmax);
  for (size_t k = 0; k < ours.size(); ++k) {
    const ImportedFace& f = *ours[k];
    ASSERT_TRUE(f.trim.has_value());
    const Eigen::Vector2d lo = f.trim->lo(), hi = f.trim->hi();
    const double tolerance = BRep_Tool::Tolerance(theirs[k]);
    for (int i = 0; i < 10000; ++i) {
      const Eigen::Vector2d uv(lo[0] + (hi[0] - lo[0]) * unit(rng),
                               lo[1] + (hi[1] - lo[1]) * unit(rng));
      const double u_theirs = f.reversed ? lo[0] + hi[0] - uv[0] : uv[0];
      BRepClass_FaceClassifier classifier(theirs[k], gp_Pnt2d(u_theirs, uv[1]), tolerance);
      const TopAbs_State state = classifier.State();
      if (state == TopAbs_ON) {
        ++on;
        continue;
      }
      // The stated band: within 1e-9 of the domain's diagonal of a loop (OCCT's classifier works
      // to its edge tolerances there), either answer is accepted.
      if (std::abs(f.trim->Nearest(uv).signed_distance) <= 1e-9 * (hi - lo).norm()) continue;
      ++checked;
      if (f.trim->Contains(uv) == (state == TopAbs_IN)) continue;
      // A point Open CASCADE calls inside that lies off the part's bounding box cannot be on
      // the part: its classifier is wrong there (the IGES plate's hole walls come with edge
      // orientations opposite to their pcurves, and it calls the whole cylinder beyond the
      // plate "in"). Counted apart; every other disagreement is ours.
      const Eigen::Vector3d x = f.surface.Evaluate(uv[0], uv[1], 0).S;
      const bool off_part =
          (x.array() < part_lo.array() - 1e-6).any() || (x.array() > part_hi.array() + 1e-6).any();
      if (state == TopAbs_IN && off_part) {
        ++reference_wrong;
      } else {
        ++disagreements;
      }
    }
  }
  std::printf(
      "%s (%s): %zu faces in %.2f s, %d points classified, %d on a boundary, %d "
      "disagreements, %d where Open CASCADE's answer is off the part\n",
      fx.name, step ? "STEP" : "IGES", ours.size(), seconds, checked, on, disagreements,
      reference_wrong);
  EXPECT_EQ(disagreements, 0);
  EXPECT_LT(seconds, 2.0);
  // Metres: the first face's points lie within the part's bounding box, in metres.
  const Eigen::Vector3d p =
      ours[0]
          ->surface
          .Evaluate(0.5 * (ours[0]->trim->lo()[0] + ours[0]->trim->hi()[0]),
                    0.5 * (ours[0]->trim->lo()[1] + ours[0]->trim->hi()[1]), 0)
          .S;
  EXPECT_LT(p.norm(), 2.0 * size);
}

INSTANTIATE_TEST_SUITE_P(Fixtures, ImportTest,
                         ::testing::Combine(::testing::Range(0, 5), ::testing::Bool()),
                         [](const auto& p) {
                           return std::string(kFixtures[std::get<0>(p.param)].name) +
                                  (std::get<1>(p.param) ? "_step" : "_iges");
                         });

std::string ErrorOf(const std::string& path) {
  try {
    ImportCad(path);
  } catch (const ImportError& e) {
    return e.what();
  }
  return "(imported)";
}

TEST(ImportTest, BadFilesAreNamed) {
  const std::string d = Dir();
  EXPECT_THAT(ErrorOf(d + "/missing.step"), HasSubstr("missing.step: no such file"));
  std::ofstream(d + "/empty.step").close();
  EXPECT_THAT(ErrorOf(d + "/empty.step"), HasSubstr("empty.step: the file is empty"));
  std::ofstream(d + "/text.step") << "this is not a STEP file\n";
  EXPECT_THAT(ErrorOf(d + "/text.step"), HasSubstr("text.step: not a readable STEP file"));
  std::ofstream(d + "/text.igs") << "this is not an IGES file\n";
  EXPECT_THAT(ErrorOf(d + "/text.igs"), HasSubstr("text.igs:"));
  std::ofstream(d + "/part.obj") << "v 0 0 0\n";
  EXPECT_THAT(ErrorOf(d + "/part.obj"), HasSubstr("part.obj: unknown extension \".obj\""));
  // A STEP file cut short.
  const std::string whole = Write(PlateWithHoles(), "to_truncate", true);
  std::ifstream in(whole);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(d + "/truncated.step") << text.substr(0, text.size() / 3);
  const std::string truncated = ErrorOf(d + "/truncated.step");
  EXPECT_THAT(truncated, HasSubstr("truncated.step"));
}

}  // namespace
}  // namespace tangent::cad

namespace tangent::cad {
namespace {

// The part's extent in metres, from the points of its faces' trimmed boundaries (the
// surfaces themselves may run beyond their faces).
double Across(const ImportedPart& part) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const ImportedBody& b : part.bodies) {
    for (const ImportedFace& f : b.faces) {
      for (const nurbs::TrimmedDomain::Chord& c : f.trim->chords()) {
        const Eigen::Vector3d p = f.surface.Evaluate(c.a[0], c.a[1], 0).S;
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
  }
  return (hi - lo).norm();
}

TEST(ImportTest, LengthsComeOutInMetresWhateverTheFilesUnit) {
  const double expected = 1e-3 * std::sqrt(100.0 * 100.0 + 60.0 * 60.0 + 8.0 * 8.0);
  // IGES: Open CASCADE's writer converts the millimetre shape into the file's unit.
  for (const char* unit : {"MM", "INCH", "M"}) {
    const double across =
        Across(ImportCad(Write(PlateWithHoles(), std::string("units_") + unit, false, unit)));
    std::printf("IGES in %s: %.9f m across\n", unit, across);
    EXPECT_NEAR(across, expected, 1e-9) << unit;
  }
  // STEP: the millimetre file, and the same numbers declared in metres and in inches (its
  // unit definition edited; Open CASCADE 7.6's STEP writer labels a unit without converting
  // consistently, so the files are made by hand from the millimetre one).
  const std::string mm = Write(PlateWithHoles(), "units_step_mm", true, "MM");
  std::ifstream in(mm);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string milli = "SI_UNIT(.MILLI.,.METRE.)";
  ASSERT_NE(text.find(milli), std::string::npos);
  EXPECT_NEAR(Across(ImportCad(mm)), expected, 1e-9);
  std::string metres = text;
  metres.replace(metres.find(milli), milli.size(), "SI_UNIT($,.METRE.)");
  std::ofstream(Dir() + "/units_step_m.step") << metres;
  const double across_m = Across(ImportCad(Dir() + "/units_step_m.step"));
  std::printf("STEP, the millimetre numbers declared in metres: %.6f m across\n", across_m);
  EXPECT_NEAR(across_m, 1e3 * expected, 1e-6);
}

}  // namespace
}  // namespace tangent::cad

namespace tangent::cad {
namespace {

TEST(ImportTest, TangentImportWritesASceneThatLoadsWithItsTrims) {
  const std::string part = Write(FilletedBox(), "cli_filleted_box", true);
  const std::string scene = Dir() + "/cli_filleted_box.json";
  std::filesystem::remove(scene);
  const std::string command = std::string(TANGENT_IMPORT) + " " + part + " -o " + scene + " -q";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const auto s = server::LoadScene(scene);
  ASSERT_EQ(s->surfaces.size(), 26u);                  // 6 planes, 12 cylinders, 8 spheres
  EXPECT_EQ(s->device.id, std::optional<int64_t>(1));  // named for tangentd (--device-id)
  // In metres from a fresh process too (whose translators nothing had initialized: it once
  // wrote the box's millimetres as metres): the 40 x 30 x 20 mm box spans 0.04 m.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const server::SceneSurface& f : s->surfaces) {
    EXPECT_TRUE(f.trim.has_value()) << f.name;
    for (int i = 0; i < f.surface.num_u(); ++i) {
      for (int j = 0; j < f.surface.num_v(); ++j) {
        lo = lo.cwiseMin(f.surface.point(i, j));
        hi = hi.cwiseMax(f.surface.point(i, j));
      }
    }
  }
  EXPECT_NEAR((hi - lo).maxCoeff(), 0.040, 1e-9);
  // A file that cannot be imported: exit status 1 and the reason on stderr.
  const std::string bad =
      std::string(TANGENT_IMPORT) + " " + Dir() + "/missing.step -q 2>/dev/null";
  EXPECT_NE(std::system(bad.c_str()), 0);
}

}  // namespace
}  // namespace tangent::cad

namespace tangent::cad {
namespace {

// Names and colours (XCAF): a part named "bracket" coloured blue with one face red, written by
// Open CASCADE's XCAF writers to STEP and IGES, comes back with its label and colours on the
// body and on its faces (the red face its own, the others the body's); the bodies keep their
// stable names ("solid 0"), and tangent-import writes labels and colours into the scene.
TEST(ImportTest, NamesAndColoursComeFromTheFile) {
  const TopoDS_Shape box = FilletedBox();
  TopoDS_Face red_face;
  for (TopExp_Explorer x(box, TopAbs_FACE); x.More(); x.Next()) {
    red_face = TopoDS::Face(x.Current());
    break;
  }
  for (bool step : {true, false}) {
    SCOPED_TRACE(step ? "STEP" : "IGES");
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    Handle(XCAFDoc_ColorTool) colours = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    const TDF_Label part = shapes->AddShape(box, false);
    TDataStd_Name::Set(part, "bracket");
    colours->SetColor(part, Quantity_Color(0.0, 0.0, 1.0, Quantity_TOC_sRGB), XCAFDoc_ColorSurf);
    const TDF_Label face = shapes->AddSubShape(part, red_face);
    ASSERT_FALSE(face.IsNull());
    colours->SetColor(face, Quantity_Color(1.0, 0.0, 0.0, Quantity_TOC_sRGB), XCAFDoc_ColorSurf);
    const std::string path = Dir() + (step ? "/named_bracket.step" : "/named_bracket.igs");
    Interface_Static::SetCVal("xstep.cascade.unit", "MM");
    if (step) {
      STEPCAFControl_Writer w;
      Interface_Static::SetCVal("write.step.unit", "MM");
      ASSERT_TRUE(w.Transfer(doc, STEPControl_AsIs));
      ASSERT_EQ(w.Write(path.c_str()), IFSelect_RetDone);
    } else {
      IGESControl_Controller::Init();
      Interface_Static::SetCVal("write.iges.unit", "MM");
      Interface_Static::SetIVal("write.iges.brep.mode", 1);  // faces with their loops
      IGESCAFControl_Writer w;
      ASSERT_TRUE(w.Transfer(doc));
      ASSERT_TRUE(w.Write(path.c_str()));
    }
    const ImportedPart imported = ImportCad(path);
    ASSERT_EQ(imported.bodies.size(), 1u);
    const ImportedBody& b = imported.bodies[0];
    EXPECT_EQ(b.name, "solid 0");
    if (step) {
      EXPECT_EQ(b.label, "bracket");  // IGES 5.3 names entities, not solids
    }
    ASSERT_TRUE(b.colour.has_value());
    EXPECT_NEAR((*b.colour)[0], 0.0, 1e-3);
    EXPECT_NEAR((*b.colour)[2], 1.0, 1e-3);
    int red = 0, blue = 0;
    for (const ImportedFace& f : b.faces) {
      ASSERT_TRUE(f.colour.has_value()) << f.name;
      red += (*f.colour)[0] > 0.99 && (*f.colour)[2] < 0.01;
      blue += (*f.colour)[2] > 0.99 && (*f.colour)[0] < 0.01;
    }
    EXPECT_EQ(red, 1);
    EXPECT_EQ(blue, static_cast<int>(b.faces.size()) - 1);
    bool reported = false;
    for (const std::string& line : ReportLines(imported))
      reported = reported || line.find("colour (1.000, 0.000, 0.000)") != std::string::npos;
    EXPECT_TRUE(reported);
  }
}

// A file that crashes Open CASCADE's STEP reader (the import fuzzer's finding, kept in
// fuzz/regressions/cad/: a face bound whose reference is the wrong entity, which the reader
// dereferences as null in StepShape_FaceBound::Bound) is an ImportError naming the file and the
// signal; the import ran in its own process, so this one goes on, and the next import works.
TEST(ImportTest, AFileThatCrashesOpenCascadeIsAnImportError) {
  std::ifstream in(std::string(TANGENT_FUZZ_REGRESSIONS) + "/cad/step_face_bound_null",
                   std::ios::binary);
  ASSERT_TRUE(in);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string path = Dir() + "/crashes_occt.step";
  std::ofstream(path, std::ios::binary) << bytes.substr(1);  // the fuzzer's format byte off
  try {
    ImportCad(path);
    ADD_FAILURE() << "imported";
  } catch (const ImportError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("crashes_occt.step: Open CASCADE crashed reading it (signal 11"));
  }
  EXPECT_EQ(ImportCad(Write(FilletedBox(), "after_crash", true)).bodies.size(), 1u);
  // An import that runs past its time is stopped and named (here: no time at all).
  ImportOptions no_time;
  no_time.timeout_seconds = 0.0;
  try {
    ImportCad(Write(FilletedBox(), "no_time", true), no_time);
    ADD_FAILURE() << "imported";
  } catch (const ImportError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("no_time.step: the import took longer than 0 s and was stopped"));
  }
}

TEST(ImportTest, ASceneBodyTakesItsFacesFromACadFile) {
  const std::string part = Write(PlateWithHoles(), "scene_plate", true);
  const std::string text = R"({"bodies": [{"name": "plate", "fixed": true, "cad": ")" + part +
                           R"("}, {"name": "b", "mass": 1}], "surfaces": [],
                               "grasp": {"body": "b"}})";
  const auto s = server::ParseScene(text, "parts.json", Dir());
  ASSERT_EQ(s->surfaces.size(), 8u);  // the box's six faces less the two cut through, 2 walls
  for (const server::SceneSurface& f : s->surfaces) {
    EXPECT_EQ(f.body, 0);
    EXPECT_TRUE(f.trim.has_value());
    EXPECT_EQ(f.name.rfind("plate/solid 0 face ", 0), 0u) << f.name;
  }
  EXPECT_NE(s->load_log[0].find("body plate: 8 faces from"), std::string::npos) << s->load_log[0];
  try {
    server::ParseScene(R"({"bodies": [{"name": "plate", "fixed": true, "cad": "nowhere.step"},
                                      {"name": "b", "mass": 1}], "surfaces": [],
                           "grasp": {"body": "b"}})",
                       "parts.json", Dir());
    ADD_FAILURE() << "accepted";
  } catch (const server::SceneError& e) {
    EXPECT_THAT(e.what(), HasSubstr("parts.json: bodies[0].cad:"));
    EXPECT_THAT(e.what(), HasSubstr("nowhere.step: no such file"));
  }
}

}  // namespace
}  // namespace tangent::cad

namespace tangent::cad {
namespace {

// The imported-parts demo's STEP files (scenes/parts/, written by tangent-demo-parts) still
// import to the shapes cad/demo_parts.h builds: the same faces, knots, control points (to
// 1e-12 m) and loops. A change to the builders that is not written out fails here.
TEST(ImportTest, TheDemoPartsAreWhatTheirGeneratorBuilds) {
  for (const auto& [name, shape] :
       {std::pair<std::string, TopoDS_Shape>{"peg_plate", demo::PegPlate()},
        std::pair<std::string, TopoDS_Shape>{"peg", demo::Peg()}}) {
    const ImportedPart kept =
        ImportCad(std::string(TANGENT_SCENES_DIR) + "/parts/" + name + ".step");
    const ImportedPart built = ImportCad(Write(shape, "demo_" + name, true));
    ASSERT_EQ(kept.bodies.size(), 1u) << name;
    ASSERT_EQ(built.bodies.size(), 1u) << name;
    const std::vector<ImportedFace>&a = kept.bodies[0].faces, &b = built.bodies[0].faces;
    ASSERT_EQ(a.size(), b.size()) << name;
    EXPECT_EQ(a.size(), name == "peg" ? 4u : 8u);
    for (size_t f = 0; f < a.size(); ++f) {
      EXPECT_EQ(a[f].kind, b[f].kind) << name << " face " << f;
      const nurbs::NurbsSurface &x = a[f].surface, &y = b[f].surface;
      ASSERT_EQ(x.knots_u().knots(), y.knots_u().knots()) << name << " face " << f;
      ASSERT_EQ(x.knots_v().knots(), y.knots_v().knots()) << name << " face " << f;
      double worst = 0.0;
      for (size_t i = 0; i < x.weighted_points().size(); ++i) {
        worst = std::max(worst,
                         (x.weighted_points()[i] - y.weighted_points()[i]).cwiseAbs().maxCoeff());
      }
      EXPECT_LE(worst, 1e-12) << name << " face " << f;
      ASSERT_EQ(a[f].trim.has_value(), b[f].trim.has_value());
      if (a[f].trim) {
        EXPECT_EQ(a[f].trim->loops().size(), b[f].trim->loops().size());
      }
    }
  }
}

}  // namespace
}  // namespace tangent::cad
