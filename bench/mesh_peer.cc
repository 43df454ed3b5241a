// What exactness buys (issue 18 item 4): the approach a mesh-based haptic library would take —
// FCL's distance query between certified tessellations of the two surfaces — against our tracked
// contact, on the same pair, the same poses, in the same run.
//
// The pair: a rational patch sheared to 15°, face down over a torus, moved along a hand-like
// path (1000 poses 1 ms apart: ~7 mm and ~0.3 rad in all, as in tests/contact/tracker_test.cc).
// Ours: the servo's contact term (optimizer::SurfaceContactTerm: the tracker's step, the
// exactness check, a full solve when it is not exact) per pose. FCL: fcl::distance between
// BVHModel<OBBRSS> of nurbs::Tessellate meshes at certified bounds of 1 mm … 5 µm (each vertex on
// the surface, every surface point within the bound of the mesh), per pose. Both against a fresh
// extremal solve at each pose (the exact distance). Reports per-query time (median over the
// path, and as a ratio to ours), the largest distance error (m), and the meshes' sizes.
//
//   ./build/bench/mesh_peer [--poses 1000] [--tolerances 1e-3,1e-4,2e-5,5e-6]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/distance.h>

#include "bench/sample_stats.h"
#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "nurbs/tessellation.h"
#include "optimizer/contacts.h"
#include "testing/contact_scenes.h"

using namespace tangent;
using contact::BodyPose;
using contact::Vector7d;
using contact::testing::Coordinates;

namespace {

// The patch's pose along the path at time t (s).
Vector7d Patch(double t) {
  const Eigen::Quaterniond rot(
      Eigen::AngleAxisd(0.2 + 0.3 * t, Eigen::Vector3d::UnitZ()) *
      Eigen::AngleAxisd(std::numbers::pi + 0.1 * std::sin(3 * t), Eigen::Vector3d::UnitX()));
  return Coordinates({0.004 * std::sin(2 * t), 0.003 * t, 0.025 - 0.006 * t}, rot);
}

std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> Model(const nurbs::TriangleMesh& mesh) {
  std::vector<fcl::Vector3d> pts(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> tris;
  tris.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    tris.emplace_back(static_cast<size_t>(t[0]), static_cast<size_t>(t[1]),
                      static_cast<size_t>(t[2]));
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  model->beginModel();
  model->addSubModel(pts, tris);
  model->endModel();
  return model;
}

fcl::Transform3d ToFcl(const Vector7d& q) {
  fcl::Transform3d x = fcl::Transform3d::Identity();
  x.linear() = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
  x.translation() = q.head<3>();
  return x;
}

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  int poses = 1000;
  std::vector<double> tolerances = {1e-3, 1e-4, 2e-5, 5e-6};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--poses") && i + 1 < argc) {
      poses = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--tolerances") && i + 1 < argc) {
      tolerances.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) tolerances.push_back(std::stod(item));
    } else {
      std::fprintf(stderr,
                   "mesh_peer: unknown argument \"%s\" (usage: --poses N --tolerances a,b,...)\n",
                   argv[i]);
      return 2;
    }
  }
  if (poses < 2 || tolerances.empty()) {
    std::fprintf(stderr, "mesh_peer: need --poses >= 2 and at least one tolerance\n");
    return 2;
  }
  const nurbs::NurbsSurface patch =
      nurbs::MakeShearedPatch(15 * std::numbers::pi / 180, 0.08, 0.01, true);
  const nurbs::NurbsSurface torus = nurbs::MakeTorus(0.04, 0.01);
  const Vector7d q_torus = Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  const BodyPose pg = BodyPose::FromCoordinates(q_torus);
  std::vector<Vector7d> path;
  for (int k = 0; k < poses; ++k) path.push_back(Patch(1e-3 * k));

  // The exact distance at every pose: a full solve from the closest samples, then followed.
  std::vector<double> exact(path.size());
  Eigen::Vector4d u =
      contact::ClosestSamplePair(patch, BodyPose::FromCoordinates(path[0]), torus, pg, 40);
  for (size_t k = 0; k < path.size(); ++k) {
    const contact::SurfaceSurfaceExtremum e = contact::SolveSurfaceSurface(
        patch, BodyPose::FromCoordinates(path[k]), torus, pg, u, contact::kContinuation);
    exact[k] = e.beta;
    u = e.u;
  }

  // Ours: the servo's contact term at each pose.
  const Eigen::Vector4d seed =
      contact::ClosestSamplePair(patch, BodyPose::FromCoordinates(path[0]), torus, pg, 40);
  optimizer::SurfaceContactTerm term(0, &patch, 1, &torus, seed);
  auto state = term.MakeState();
  std::vector<BodyPose> body_poses = {BodyPose::FromCoordinates(path[0]), pg};
  Eigen::VectorXd r(1);
  Eigen::MatrixXd J_a(1, 7), J_b(1, 7);
  term.Evaluate(body_poses, state.get(), r, J_a, J_b);  // the start's full solve, not timed
  std::vector<double> ours_us;
  double ours_error = 0.0;
  for (size_t k = 1; k < path.size(); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    body_poses[0] = BodyPose::FromCoordinates(path[k]);
    term.Evaluate(body_poses, state.get(), r, J_a, J_b);
    ours_us.push_back(Since(t0));
    ours_error = std::max(ours_error, std::abs(r[0] - exact[k]));
  }
  const double ours = tangent::bench::Quantile(ours_us, 0.5);

  std::printf(
      "mesh_peer: %d poses of a 15°-sheared rational patch over a torus (distance %.1f → %.1f "
      "mm)\n\n",
      poses, 1e3 * exact.front(), 1e3 * exact.back());
  std::printf(
      "| method | certified bound (m) | triangles (patch + torus) | mesh build (ms) | query p50 "
      "(us) | query p99 (us) | time / ours | distance error max (m) |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  std::printf("| ours: tracked exact contact | — | — | — | %.3f | %.3f | 1 | %.1e |\n", ours,
              tangent::bench::Quantile(ours_us, 0.99), ours_error);
  for (double tol : tolerances) {
    const auto b0 = std::chrono::steady_clock::now();
    const nurbs::TriangleMesh mp = nurbs::Tessellate(patch, tol);
    const nurbs::TriangleMesh mt = nurbs::Tessellate(torus, tol);
    fcl::CollisionObjectd a(Model(mp)), b(Model(mt));
    const double build_ms = 1e-3 * Since(b0);
    b.setTransform(ToFcl(q_torus));
    std::vector<double> us;
    double error = 0.0;
    for (size_t k = 1; k < path.size(); ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      a.setTransform(ToFcl(path[k]));
      a.computeAABB();
      fcl::DistanceRequestd request(true);
      fcl::DistanceResultd result;
      fcl::distance(&a, &b, request, result);
      us.push_back(Since(t0));
      error = std::max(error, std::abs(result.min_distance - exact[k]));
    }
    const double p50 = tangent::bench::Quantile(us, 0.5);
    std::printf(
        "| FCL distance, meshes | %.0e (bounds %.1e, %.1e) | %zu + %zu | %.1f | %.2f | "
        "%.2f | %.0f | %.1e |\n",
        tol, mp.error_bound, mt.error_bound, mp.triangles.size(), mt.triangles.size(), build_ms,
        p50, tangent::bench::Quantile(us, 0.99), p50 / ours, error);
  }
  return 0;
}
