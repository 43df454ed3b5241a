// Writes the imported-parts demo's parts (cad/demo_parts.h) as STEP files, in millimetres:
//
//   tangent-demo-parts DIR      -> DIR/peg_plate.step, DIR/peg.step
//
// scenes/parts/ holds the files this wrote; tests/cad checks that they still import to the
// shapes built here.

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Writer.hxx>

#include <cstdio>
#include <filesystem>
#include <string>

#include "cad/demo_parts.h"

namespace {

bool Write(const TopoDS_Shape& shape, const std::string& path) {
  STEPControl_Writer w;
  if (w.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone) return false;
  return w.Write(path.c_str()) == IFSelect_RetDone;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tangent-demo-parts DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);
  STEPControl_Controller::Init();  // (its parameters exist from here on)
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  Interface_Static::SetCVal("write.step.unit", "MM");
  bool ok = Write(tangent::cad::demo::PegPlate(), dir + "/peg_plate.step");
  ok = Write(tangent::cad::demo::Peg(), dir + "/peg.step") && ok;
  if (!ok) {
    std::fprintf(stderr, "tangent-demo-parts: Open CASCADE could not write the parts to %s\n",
                 dir.c_str());
    return 1;
  }
  std::printf("tangent-demo-parts: %s/peg_plate.step, %s/peg.step\n", dir.c_str(), dir.c_str());
  return 0;
}
