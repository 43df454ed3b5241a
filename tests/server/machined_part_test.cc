// A real machined part in the loop (issue 37): scenes/flange_cad.json, the CAx-IF io1 flange as
// CoCreate wrote it, imported whole, and a ball the hand presses on the disc's face, drags over a
// bolt hole's rim into the hole and round its wall, out over the far rim and into the corner of
// the disc and the hub (scenes/flange_cad.path.csv, the demo's path, without device dynamics).
// Contact is declared between the two bodies: the global stage finds every face pair.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <string>

#include "tests/server/hand_drive.h"

namespace tangent::server {
namespace {

constexpr double mm = 1e-3;

TEST(MachinedPartTest, ABallHeldOnTheFlangesFaceItsHolesRimsAndWallAndTheHub) {
  const std::string dir = TANGENT_SCENES_DIR;
  auto scene = LoadScene(dir + "/flange_cad.json");
  // The flange's faces as tangent-import lists them: the disc's face (8 loops: its rim, the
  // hub and six bolt holes), the bolt holes' walls (two halves each), the hub's wall.
  auto face = [&](int k) {
    return scene->SurfaceIndex("flange/solid 0 face " + std::to_string(k));
  };
  const int disc = face(9);
  std::set<int> hole_walls, hub;
  for (int k : {10, 11, 12, 13, 14, 15, 21, 22, 23, 24, 25, 27}) hole_walls.insert(face(k));
  for (int k : {8, 18}) hub.insert(face(k));
  ASSERT_GE(disc, 0);
  const int ball = scene->BodyIndex("ball");
  int on_disc = 0, edge = 0, on_hole_wall = 0, in_hub_corner = 0;
  double deepest = 1.0;
  const HandDrive run =
      DriveAlongPath(*scene, dir + "/flange_cad.path.csv", 23000, [&](const Snapshot& snap) {
        bool disc_face = false, at_edge = false, wall = false, hub_wall = false;
        for (int c = 0; c < snap.num_contacts; ++c) {
          const TrackedContact& x = snap.contacts[c];
          const bool a = scene->surfaces[static_cast<size_t>(x.surface_a)].body != ball;
          const int s = a ? x.surface_a : x.surface_b;
          const Eigen::Vector2d uv =
              a ? Eigen::Vector2d(x.u[0], x.u[1]) : Eigen::Vector2d(x.u[2], x.u[3]);
          const auto& trim = scene->surfaces[static_cast<size_t>(s)].trim;
          const bool on_material = !trim || trim->Contains(uv);
          // Off a face's material the contact is an edge contact: measured on its trim edge.
          disc_face = disc_face || (s == disc && on_material);
          at_edge = at_edge || !on_material;
          wall = wall || hole_walls.count(s) > 0;
          hub_wall = hub_wall || hub.count(s) > 0;
        }
        on_disc += disc_face;
        edge += at_edge;
        on_hole_wall += wall;
        in_hub_corner += disc_face && hub_wall;
        deepest = std::min(deepest, snap.q[ball][2]);
      });
  std::printf(
      "flange_cad: %d ticks, worst violation %.1e m, max force %.2f N (largest step %.3f N at %.3f "
      "s), "
      "states with the ball on the disc's face %d, at an edge %d, on a bolt hole's wall %d, "
      "in the corner of the disc and the hub %d; deepest centre %.2f mm; events %d; allocations "
      "%ld; servo %.1f us per tick\n",
      run.ticks, run.worst_violation, run.max_force, run.max_force_step, run.max_force_step_at,
      on_disc, edge, on_hole_wall, in_hub_corner, deepest / mm, run.events, run.allocations,
      1e6 * run.tick_seconds / run.ticks);
  EXPECT_TRUE(run.all_finite);
  EXPECT_LE(run.worst_violation, 1e-8);
  EXPECT_GT(on_disc, 1000);       // pressed on the face
  EXPECT_GT(edge, 0);             // the hole's rim felt as an edge
  EXPECT_GT(on_hole_wall, 1000);  // round the hole's wall
  EXPECT_LT(deepest, 6.5 * mm);   // in the hole: the centre below the disc's face (6 mm) + 0.5
  EXPECT_GT(in_hub_corner, 500);  // on the disc and the hub's wall at once
  EXPECT_LE(run.max_force, scene->device.max_force + 1e-12);
  EXPECT_LE(run.max_force_step, 0.1);
  EXPECT_EQ(run.allocations, 0);
}

}  // namespace
}  // namespace tangent::server
