// Model only what a scene needs (issue 18): what declared-but-idle parts cost the servo. The
// paperclips and the same scene with N more clips that nothing acts on (no pair, joint, grasp
// or objective) are dragged in lockstep on one thread: each device state's four ticks and one
// global pass run on one scene, then on the other, alternating which goes first, so both see
// the same machine. Reports the tick and pass times of each and their ratios (the target: within
// 10 %), the modelled coordinates and offset meshes, and whether the wrenches agree bit for bit.
//
//   ./build/bench/model_cost [--idle 17] [--steps 6000]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/sample_stats.h"
#include "server/global_link.h"
#include "server/servo.h"
#include "testing/drag_path.h"
#include "testing/idle_parts.h"

using namespace tangent::server;

namespace {

using tangent::bench::Mean;
using tangent::bench::Quantile;

struct Run {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<ServoLoop> servo;
  std::unique_ptr<GlobalLink> link;
  std::vector<double> tick_us, pass_us;
  std::vector<double> forces;
  Snapshot snap;
  TickResult r;

  explicit Run(std::unique_ptr<Scene> s) : scene(std::move(s)) {
    servo = std::make_unique<ServoLoop>(*scene, ServoOptions{});
    link = std::make_unique<GlobalLink>(*servo);
  }
  void Step(const DeviceSample& s, int64_t now) {
    for (int tick = 0; tick < 4; ++tick) {
      const auto t0 = std::chrono::steady_clock::now();
      servo->Tick(&s, now + 250'000 * tick, &r);
      tick_us.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      for (double f : r.wrench.force) forces.push_back(f);
    }
    const auto t0 = std::chrono::steady_clock::now();
    servo->FillSnapshot(&snap);
    link->PassInto(servo.get(), snap);
    pass_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
};

}  // namespace

int main(int argc, char** argv) {
  int idle = 17, steps = 6000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--idle")) idle = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
  }
  Run a(LoadScene(std::string(TANGENT_SCENES_DIR) + "/paperclips.json"));
  Run b(ParseScene(tangent::testing::PaperclipsWithIdleClips(TANGENT_SCENES_DIR, idle),
                   "paperclips + idle clips", TANGENT_SCENES_DIR));
  int64_t now = 1'000'000'000;
  for (int k = 0; k < steps; ++k) {
    const DeviceSample s = tangent::bench::DragSample(k + 1, 1e-3 * k, now);
    if (k % 2 == 0) {
      a.Step(s, now);
      b.Step(s, now);
    } else {
      b.Step(s, now);
      a.Step(s, now);
    }
    now += 1'000'000;
  }
  int meshes_b = 0;
  for (const SceneSurface& s : b.scene->surfaces) meshes_b += !s.mesh.vertices.empty();
  std::printf("model_cost: %d device steps, %d ticks per scene, drag path\n", steps, 4 * steps);
  std::printf("%-28s %8s %8s %11s %11s %11s %11s\n", "scene", "bodies", "coords", "tick p50",
              "tick mean", "tick p99", "pass mean");
  for (const Run* r : {&a, &b}) {
    std::printf("%-28s %8d %8d %8.2f us %8.2f us %8.2f us %8.1f us\n",
                r == &a ? "paperclips (3 parts)" : "paperclips + idle clips",
                r->scene->mechanism.num_bodies(), r->servo->problem().mechanism().num_coordinates(),
                Quantile(r->tick_us, 0.5), Mean(r->tick_us), Quantile(r->tick_us, 0.99),
                Mean(r->pass_us));
  }
  std::printf(
      "ratios (idle / 3 parts): tick p50 %.3f, tick mean %.3f, pass mean %.3f; offset meshes "
      "built %d of %zu surfaces; wrenches identical: %s\n",
      Quantile(b.tick_us, 0.5) / Quantile(a.tick_us, 0.5), Mean(b.tick_us) / Mean(a.tick_us),
      Mean(b.pass_us) / Mean(a.pass_us), meshes_b, b.scene->surfaces.size(),
      a.forces == b.forces ? "yes" : "no");
  return a.forces == b.forces ? 0 : 1;
}
