// Real CAD files written by other systems (tests/cad/corpus/README.md), imported whole: every face
// Open CASCADE finds comes in, the material's total area matches Open CASCADE's to 1e-6, and points
// of Open CASCADE's faces lie within 1e-9 m of ours, inside our trims (issue 37).

#include <gtest/gtest.h>
#include <BRepAdaptor_Surface.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESControl_Controller.hxx>
#include <Interface_Static.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Controller.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <ShapeFix_Shape.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "cad/import.h"
#include "nurbs/area.h"

namespace tangent::cad {
namespace {

struct Entry {
  std::string file, writer, unit;
};

// gtest prints a parameter by this (the test names in ctest show the file).
void PrintTo(const Entry& e, std::ostream* os) { *os << e.file; }

std::vector<Entry> Corpus() {
  std::ifstream in(std::string(TANGENT_CORPUS_DIR) + "/corpus.tsv");
  std::vector<Entry> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    Entry e;
    std::getline(fields, e.file, '\t');
    std::getline(fields, e.writer, '\t');
    std::getline(fields, e.unit, '\t');
    out.push_back(e);
  }
  return out;
}

// The file as Open CASCADE reads it: decompressed into the test's directory if stored gzipped.
std::string Readable(const Entry& e) {
  const std::string stored = std::string(TANGENT_CORPUS_DIR) + "/" + e.file;
  if (!e.file.ends_with(".gz")) return stored;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "tangent_corpus";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / e.file.substr(0, e.file.size() - 3)).string();
  const std::string command = "gzip -dc '" + stored + "' > '" + out + "'";
  if (std::system(command.c_str()) != 0) ADD_FAILURE() << "cannot decompress " << stored;
  return out;
}

// The faces of the file as the importer sees them (XCAF read in metres, healed, bodies the
// solids, else the shells, else the whole), in its order.
std::vector<TopoDS_Face> TheirFaces(const std::string& path) {
  STEPControl_Controller::Init();
  IGESControl_Controller::Init();
  Interface_Static::SetCVal("xstep.cascade.unit", "M");
  Handle(TDocStd_Document) doc;
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
  if (path.ends_with(".igs") || path.ends_with(".iges")) {
    IGESCAFControl_Reader r;
    r.ReadFile(path.c_str());
    r.Transfer(doc);
  } else {
    STEPCAFControl_Reader r;
    r.ReadFile(path.c_str());
    r.Transfer(doc);
  }
  TDF_LabelSequence free;
  XCAFDoc_DocumentTool::ShapeTool(doc->Main())->GetFreeShapes(free);
  TopoDS_Shape shape;
  if (free.Length() == 1) {
    shape = XCAFDoc_ShapeTool::GetShape(free.Value(1));
  } else {
    TopoDS_Compound all;
    BRep_Builder builder;
    builder.MakeCompound(all);
    for (int i = 1; i <= free.Length(); ++i)
      builder.Add(all, XCAFDoc_ShapeTool::GetShape(free.Value(i)));
    shape = all;
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
    for (TopExp_Explorer x(b, TopAbs_FACE); x.More(); x.Next())
      faces.push_back(TopoDS::Face(x.Current()));
  }
  return faces;
}

// Distinct knots and their multiplicities, as Open CASCADE takes them.
void Multiplicities(const std::vector<double>& flat, TColStd_Array1OfReal* knots,
                    TColStd_Array1OfInteger* mults) {
  std::vector<double> k;
  std::vector<int> m;
  for (double t : flat) {
    if (!k.empty() && t == k.back()) {
      ++m.back();
    } else {
      k.push_back(t);
      m.push_back(1);
    }
  }
  knots->Resize(1, static_cast<int>(k.size()), false);
  mults->Resize(1, static_cast<int>(m.size()), false);
  for (size_t i = 0; i < k.size(); ++i) {
    knots->SetValue(static_cast<int>(i) + 1, k[i]);
    mults->SetValue(static_cast<int>(i) + 1, m[i]);
  }
}

// Our surface as an Open CASCADE B-spline (to project onto it with Open CASCADE's own tool).
Handle(Geom_BSplineSurface) AsOcct(const nurbs::NurbsSurface& s) {
  TColStd_Array1OfReal ku(1, 1), kv(1, 1);
  TColStd_Array1OfInteger mu(1, 1), mv(1, 1);
  Multiplicities(s.knots_u().knots(), &ku, &mu);
  Multiplicities(s.knots_v().knots(), &kv, &mv);
  TColgp_Array2OfPnt poles(1, s.num_u(), 1, s.num_v());
  TColStd_Array2OfReal weights(1, s.num_u(), 1, s.num_v());
  for (int i = 0; i < s.num_u(); ++i) {
    for (int j = 0; j < s.num_v(); ++j) {
      const Eigen::Vector3d p = s.point(i, j);
      poles(i + 1, j + 1) = gp_Pnt(p[0], p[1], p[2]);
      weights(i + 1, j + 1) = s.weight(i, j);
    }
  }
  return new Geom_BSplineSurface(poles, weights, ku, kv, mu, mv, s.degree_u(), s.degree_v());
}

class CorpusTest : public ::testing::TestWithParam<Entry> {};

TEST_P(CorpusTest, EveryFaceComesInWithOpenCascadesAreaAndPoints) {
  const Entry& e = GetParam();
  const std::string path = Readable(e);
  const ImportedPart part = ImportCad(path);
  const std::vector<TopoDS_Face> theirs = TheirFaces(path);
  std::vector<const ImportedFace*> ours;
  for (const ImportedBody& b : part.bodies) {
    for (const ImportedFace& f : b.faces) ours.push_back(&f);
  }
  std::string warnings;
  for (const std::string& w : part.report.warnings) warnings += "\n  " + w;
  ASSERT_EQ(part.report.skipped, 0) << e.file << " (" << e.writer << ")" << warnings;
  ASSERT_EQ(ours.size(), theirs.size()) << e.file;

  double area_ours = 0.0, area_theirs = 0.0, worst_point = 0.0;
  int points = 0, outside = 0, on_boundary = 0;
  for (size_t k = 0; k < theirs.size(); ++k) {
    const ImportedFace& f = *ours[k];
    ASSERT_TRUE(f.trim.has_value()) << f.name;
    area_ours += nurbs::TrimmedArea(f.surface, &*f.trim);
    GProp_GProps props;
    BRepGProp::SurfaceProperties(theirs[k], props, 1e-10);
    area_theirs += props.Mass();
    // Points of their face's material (a 9 × 9 grid of its parameters, those inside it).
    const BRepAdaptor_Surface surface(theirs[k]);
    double tolerance = 0.0;  // the largest of their face's edges' and vertices'
    for (TopExp_Explorer x(theirs[k], TopAbs_EDGE); x.More(); x.Next())
      tolerance = std::max(tolerance, BRep_Tool::Tolerance(TopoDS::Edge(x.Current())));
    for (TopExp_Explorer x(theirs[k], TopAbs_VERTEX); x.More(); x.Next())
      tolerance = std::max(tolerance, BRep_Tool::Tolerance(TopoDS::Vertex(x.Current())));
    const Handle(ShapeAnalysis_Surface) analysis = new ShapeAnalysis_Surface(AsOcct(f.surface));
    double u0, u1, v0, v1;
    BRepTools::UVBounds(theirs[k], u0, u1, v0, v1);
    for (int i = 1; i < 10; ++i) {
      for (int j = 1; j < 10; ++j) {
        const gp_Pnt2d uv(u0 + (u1 - u0) * i / 10.0, v0 + (v1 - v0) * j / 10.0);
        BRepClass_FaceClassifier inside(theirs[k], uv, 1e-9);
        if (inside.State() != TopAbs_IN) continue;
        const gp_Pnt p = surface.Value(uv.X(), uv.Y());
        const gp_Pnt2d foot = analysis->ValueOfUV(p, 1e-12);
        const double a = foot.X(), b = foot.Y(), gap = analysis->Gap();
        worst_point = std::max(worst_point, gap);
        ++points;
        if (!f.trim->Contains(Eigen::Vector2d(a, b))) {
          const nurbs::TrimmedDomain::Closest c = f.trim->Nearest(Eigen::Vector2d(a, b));
          const double d3 =
              (f.surface.Evaluate(a, b, 0).S - f.surface.Evaluate(c.point[0], c.point[1], 0).S)
                  .norm();
          // Off our material: by no more than the file's tolerance there (a point on their
          // boundary, within what the file allows), or an error.
          ++(d3 <= tolerance ? on_boundary : outside);
        }
      }
    }
  }
  std::printf(
      "%-30s %-40s %4zu faces, %5d points (%d on the boundary within tolerance), worst "
      "%.2e m; area %.6e m2, %.1e from theirs\n",
      e.file.c_str(), e.writer.c_str(), theirs.size(), points, on_boundary, worst_point, area_ours,
      std::abs(area_ours / area_theirs - 1.0));
  EXPECT_NEAR(area_ours / area_theirs, 1.0, 1e-6) << e.file;
  EXPECT_LE(worst_point, 1e-9) << e.file;
  EXPECT_EQ(outside, 0) << e.file << ": points of their material outside our trims";
  EXPECT_GT(points, static_cast<int>(theirs.size())) << e.file;
}

INSTANTIATE_TEST_SUITE_P(RealFiles, CorpusTest, ::testing::ValuesIn(Corpus()),
                         [](const ::testing::TestParamInfo<Entry>& param) {
                           std::string name = param.param.file;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

TEST(CorpusManifestTest, HoldsTwentyFilesOrMore) {
  const std::vector<Entry> corpus = Corpus();
  EXPECT_GE(corpus.size(), 20u);
  for (const Entry& e : corpus) {
    EXPECT_TRUE(std::filesystem::exists(std::string(TANGENT_CORPUS_DIR) + "/" + e.file)) << e.file;
  }
}

}  // namespace
}  // namespace tangent::cad
