// The peg-in-hole scene's servo budget against the paperclips' (issue 16: "servo p99 within the
// same budget as the paperclips, measured in the same run"). Both scenes run on one thread in
// lockstep: each device state's four 4 kHz ticks run on one scene, then on the other (which goes
// first alternates), the paperclips on the demo's drag and the peg on its own hand path
// (scenes/peg_in_hole.path.csv: across the plate, over the rim, into the hole, round its wall,
// out). A global pass runs every 4 ms on each, outside the timed ticks. Reports tick p50/p99/
// p99.9 of each and the peg's p99 as a ratio of the paperclips'.
//
//   ./build/bench/peg_budget [--steps 20000]   (device states; 20 s of both paths)
//                            [--only peg|paperclips]  (one scene: for profilers such as callgrind)
//                            [--peg-scene peg_in_hole_cad]  (the same parts imported from STEP,
//                                                    issue 17's demo: its target is 1.5;
//                                                    peg_in_hole_cad_bodies: the same with
//                                                    contact declared between the bodies;
//                                                    peg_in_hole_poles_on_axis: the end
//                                                    sphere's poles on the axis, where the
//                                                    plate and floor touch it, issue 34;
//                                                    tile_over_hole: two trimmed faces
//                                                    meeting edge on edge on their own
//                                                    path, issue 34: its target is 1.5)
//                            [--target R]            (the p99 ratio to meet; default 1, or 1.5
//                                                    for the peg_in_hole_cad scenes and the
//                                                    tile)

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/sample_stats.h"
#include "server/global_link.h"
#include "server/phantom.h"
#include "server/servo.h"
#include "testing/drag_path.h"
#include "testing/peg_variants.h"

using namespace tangent::server;

namespace {

using tangent::bench::Quantile;

struct Run {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<ServoLoop> servo;
  std::unique_ptr<GlobalLink> link;
  std::vector<double> tick_us;
  double max_violation = 0.0;
  Snapshot snap;
  TickResult r;

  explicit Run(const std::string& name)
      : scene(name == "peg_in_hole_poles_on_axis"
                  ? tangent::testing::PegWithPolesOnAxis(TANGENT_SCENES_DIR)
                  : LoadScene(std::string(TANGENT_SCENES_DIR) + "/" + name + ".json")) {
    servo = std::make_unique<ServoLoop>(*scene, ServoOptions{});
    link = std::make_unique<GlobalLink>(*servo);
  }
  void Step(const DeviceSample& s, int64_t now, bool pass) {
    for (int tick = 0; tick < 4; ++tick) {
      const auto t0 = std::chrono::steady_clock::now();
      servo->Tick(&s, now + 250'000 * tick, &r);
      tick_us.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      max_violation = std::max(max_violation, r.violation);
    }
    if (!pass) return;
    servo->FillSnapshot(&snap);
    link->PassInto(servo.get(), snap);
  }
};

}  // namespace

int main(int argc, char** argv) {
  int steps = 20000;
  std::string only;  // "", "peg" or "paperclips"
  std::string peg_scene = "peg_in_hole";
  double target = 0.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--only")) only = argv[i + 1];
    if (!std::strcmp(argv[i], "--peg-scene")) peg_scene = argv[i + 1];
    if (!std::strcmp(argv[i], "--target")) target = std::atof(argv[i + 1]);
  }
  const bool two_trimmed = peg_scene == "tile_over_hole";
  if (!(target > 0.0)) {
    target = peg_scene.rfind("peg_in_hole_cad", 0) == 0 || two_trimmed ? 1.5 : 1.0;
  }
  // The scene's own hand path where it has one (scenes/NAME.path.csv), else the peg's.
  const std::string path_name = (two_trimmed ? peg_scene : "peg_in_hole") + ".path.csv";
  std::ifstream f(std::string(TANGENT_SCENES_DIR) + "/" + path_name);
  std::stringstream text;
  text << f.rdbuf();
  const HandTrajectory peg_path = HandTrajectory::FromCsv(text.str(), path_name);
  Run clips("paperclips"), peg(peg_scene);
  int64_t now = 1'000'000'000;
  for (int k = 0; k < steps; ++k) {
    const double t = 1e-3 * k;
    const DeviceSample a = tangent::bench::DragSample(k + 1, t, now);
    DeviceSample b = a;
    const Eigen::Vector3d p = peg_path.At(t);
    for (int i = 0; i < 3; ++i) b.position[i] = p[i];
    const bool pass = k % 4 == 3;
    if (only == "peg") {
      peg.Step(b, now, pass);
    } else if (only == "paperclips") {
      clips.Step(a, now, pass);
    } else if (k % 2 == 0) {
      clips.Step(a, now, pass);
      peg.Step(b, now, pass);
    } else {
      peg.Step(b, now, pass);
      clips.Step(a, now, pass);
    }
    now += 1'000'000;
  }
  auto line = [](const char* name, const Run& r) {
    std::printf("%-16s tick p50 %6.2f us  p99 %6.2f us  p99.9 %6.2f us  max violation %.1e m\n",
                name, Quantile(r.tick_us, 0.5), Quantile(r.tick_us, 0.99),
                Quantile(r.tick_us, 0.999), r.max_violation);
  };
  if (!only.empty()) {
    std::printf("peg_budget: %d device states, 4 ticks each, %s only\n", steps, only.c_str());
    line(only.c_str(), only == "peg" ? peg : clips);
    return 0;
  }
  std::printf("peg_budget: %d device states, 4 ticks each, both scenes in lockstep on one thread\n",
              steps);
  line("paperclips", clips);
  line(peg_scene.c_str(), peg);
  const double ratio = Quantile(peg.tick_us, 0.99) / Quantile(clips.tick_us, 0.99);
  std::printf("peg p99 / paperclips p99 = %.2f (target <= %g: %s)\n", ratio, target,
              ratio <= target ? "met" : "NOT MET");
  return 0;
}
