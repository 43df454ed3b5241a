// Writes the CAD fuzzer's seed corpus (cad_fuzzer.cc: first byte 0 for STEP, 1 for IGES, then
// the file): parts Open CASCADE builds and writes — a box with a hole, a cylinder, a filleted
// box — small enough for libFuzzer's mutations to reach every section of the files.
//
//   tangent-cad-seeds DIR

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Writer.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <gp_Ax2.hxx>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

// The written file with its format byte in front.
bool Seed(const TopoDS_Shape& shape, const std::string& dir, const std::string& name, bool iges) {
  const std::string tmp = dir + "/" + name + (iges ? ".tmp.igs" : ".tmp.step");
  if (iges) {
    IGESControl_Controller::Init();
    IGESControl_Writer w("MM", 1);
    w.AddShape(shape);
    w.ComputeModel();
    if (!w.Write(tmp.c_str())) return false;
  } else {
    STEPControl_Writer w;
    if (w.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone) return false;
    if (w.Write(tmp.c_str()) != IFSelect_RetDone) return false;
  }
  std::ifstream in(tmp, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  std::ofstream out(dir + "/" + name + (iges ? "_iges" : "_step"), std::ios::binary);
  out.put(iges ? 1 : 0);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::filesystem::remove(tmp);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tangent-cad-seeds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  Interface_Static::SetCVal("write.step.unit", "MM");
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(20, 10, 4).Shape();
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(10, 5, -1), gp_Dir(0, 0, 1)), 2, 6).Shape();
  const TopoDS_Shape plate = BRepAlgoAPI_Cut(box, hole).Shape();
  const TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(3, 8).Shape();
  const TopoDS_Shape cube = BRepPrimAPI_MakeBox(10, 10, 10).Shape();
  BRepFilletAPI_MakeFillet fillet(cube);
  for (TopExp_Explorer e(cube, TopAbs_EDGE); e.More(); e.Next()) {
    fillet.Add(1.0, TopoDS::Edge(e.Current()));
    break;
  }
  const TopoDS_Shape filleted = fillet.Shape();
  int written = 0;
  for (bool iges : {false, true}) {
    written += Seed(plate, dir, "plate", iges);
    written += Seed(cylinder, dir, "cylinder", iges);
    written += Seed(filleted, dir, "filleted", iges);
  }
  std::printf("tangent-cad-seeds: %d seeds in %s\n", written, dir.c_str());
  return written == 6 ? 0 : 1;
}
