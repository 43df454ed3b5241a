#include "contact/global_minima.h"

#include <algorithm>

namespace tangent::contact::internal {

bool SamePoints(const GlobalContact& x, const GlobalContact& y) {
  return x.a == y.a && x.b == y.b && (x.p_a - y.p_a).norm() < kSamePoint &&
         (x.p_b - y.p_b).norm() < kSamePoint;
}

void AddFound(const GlobalContact& c, std::vector<GlobalContact>* out) {
  if (std::none_of(out->begin(), out->end(),
                   [&](const GlobalContact& o) { return SamePoints(o, c); })) {
    out->push_back(c);
  }
}

void MinimaBeside(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                  const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                  const SurfaceSurfaceExtremum& saddle, const SurfacePairEval& at,
                  const RelativeCurvature& rc, const GlobalOptions& options, int a, int b,
                  std::vector<GlobalContact>* out) {
  for (const double side : {1.0, -1.0}) {
    SurfacePairEval q;
    SurfaceSurfaceExtremum e;
    if (!MinimumBesideSaddle(f, pose_f, g, pose_g, saddle, at, rc, side, &e, &q) ||
        !(e.beta < options.activation) || !(e.beta > -options.max_penetration) ||
        side * (e.p_g - saddle.p_g).dot(rc.min_direction) < kSamePoint) {
      continue;
    }
    AddFound({a, b, e.u, e.beta, e.p_f, e.p_g}, out);
  }
}

void NestedPairMinimum(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                       const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                       const GlobalOptions& options, int a, int b,
                       std::vector<GlobalContact>* out) {
  const Eigen::Vector4d seed = ClosestSamplePair(f, pose_f, g, pose_g, 4);
  SurfacePairEval at;
  const SurfaceSurfaceExtremum e = SolveSurfaceSurface(f, pose_f, g, pose_g, seed, {}, &at);
  const bool taken = (e.status == ExtremalStatus::kConverged || LineContinuum(options, e, at)) &&
                     e.beta < options.activation && e.beta > -options.max_penetration &&
                     e.alignment < 0.0;
  if (!taken) return;
  if (const RelativeCurvature rc = RelativeCurvatureOf(at);
      e.status == ExtremalStatus::kConverged && rc.crossing) {
    MinimaBeside(f, pose_f, g, pose_g, e, at, rc, options, a, b, out);
    return;
  }
  AddFound({a, b, e.u, e.beta, e.p_f, e.p_g}, out);
}

}  // namespace tangent::contact::internal
