#include "contact/relative_curvature.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "contact/box_newton.h"
#include "contact/solver_inputs.h"

namespace tangent::contact {

bool ShapeOperator(const PlacedSurfacePoint& p, Eigen::Matrix3d* K_W) {
  K_W->setZero();
  const nurbs::SurfacePoint& s = p.world;
  const double N = p.N_W.norm();
  // A pole: the chart's T loses rank (|S_u × S_v| → 0) and I⁻¹ blows up.
  if (p.pole || !(N > 1e-12 * s.S_u.squaredNorm() + 1e-12 * s.S_v.squaredNorm())) return false;
  const Eigen::Vector3d n = p.N_W / N;
  Eigen::Matrix<double, 3, 2> T;
  T << s.S_u, s.S_v;
  const Eigen::Matrix2d I = T.transpose() * T;
  Eigen::Matrix2d II;
  II << s.S_uu.dot(n), s.S_uv.dot(n), s.S_uv.dot(n), s.S_vv.dot(n);
  const Eigen::Matrix2d I_inv = I.inverse();
  *K_W = -(T * I_inv * II * I_inv * T.transpose());
  return K_W->allFinite();
}

RelativeCurvature RelativeCurvatureOf(const SurfacePairEval& e) {
  RelativeCurvature out;
  Eigen::Matrix3d K_f, K_g;
  if (!ShapeOperator(e.f, &K_f) || !ShapeOperator(e.g, &K_g)) return out;
  const Eigen::Vector3d n_g = e.g.N_W.normalized();
  const Eigen::Vector3d n_f = e.f.N_W.normalized();
  // Facing normals (an extremum of facing surfaces): n_f = −n_g up to the solve's tolerance.
  if (!(n_f.dot(n_g) < 0.0)) return out;
  const Eigen::Vector3d x = e.g.world.S_u.normalized();
  const Eigen::Vector3d y = n_g.cross(x);
  Eigen::Matrix<double, 3, 2> P;
  P << x, y;
  // g offset by β (the surface f touches at the extremum): K_g (1 + β K_g)⁻¹ on the tangent
  // plane, in the frame (x, y).
  const double beta = e.d.dot(n_g);
  const Eigen::Matrix2d k_g = P.transpose() * K_g * P;
  const Eigen::Matrix2d offset = Eigen::Matrix2d::Identity() + beta * k_g;
  if (!(std::abs(offset.determinant()) > 1e-9)) return out;
  const Eigen::Matrix2d M = P.transpose() * K_f * P + k_g * offset.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (M + M.transpose()));
  out.eigenvalues = es.eigenvalues();
  out.min_direction = (P * es.eigenvectors().col(0)).normalized();
  const double scale = out.eigenvalues.cwiseAbs().maxCoeff();
  out.valid = out.eigenvalues.allFinite() && out.min_direction.allFinite();
  out.crossing = out.valid && out.eigenvalues[0] < -kCrossingTolerance * scale;
  return out;
}

Eigen::Vector4d ParameterStepAlong(const SurfacePairEval& e, const Eigen::Vector3d& w) {
  Eigen::Vector4d step;
  for (int side = 0; side < 2; ++side) {
    const nurbs::SurfacePoint& s = side == 0 ? e.f.world : e.g.world;
    Eigen::Matrix<double, 3, 2> T;
    T << s.S_u, s.S_v;
    step.segment<2>(2 * side) = (T.transpose() * T).inverse() * (T.transpose() * w);
  }
  return step;
}

bool MinimumBesideSaddle(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                         const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                         const SurfaceSurfaceExtremum& saddle, const SurfacePairEval& at,
                         const RelativeCurvature& rc, double side, SurfaceSurfaceExtremum* out,
                         SurfacePairEval* out_eval) {
  const double radius = 1.0 / std::max(rc.eigenvalues.cwiseAbs().maxCoeff(), 1e-300);
  const Eigen::Vector4d step = ParameterStepAlong(at, rc.min_direction);
  if (!step.allFinite()) return false;
  const internal::PairBox box = internal::PairBoxOf(f, g);
  Eigen::Vector4d best = saddle.u;
  double best_distance = saddle.beta;
  for (double xi = 0.01 * radius; xi <= 2.0 * radius; xi *= 2.0) {
    const Eigen::Vector4d x =
        internal::ClampOrWrap<4>(saddle.u + side * xi * step, box.lo, box.hi, box.periodic);
    const Eigen::Vector3d p_W = pose_f.Point(f.Evaluate(x[0], x[1], 0).S);
    const PointSurfaceExtremum q = SolvePointSurface(p_W, g, pose_g, x.tail<2>());
    if (q.status != ExtremalStatus::kConverged || !(q.distance < best_distance)) break;
    best << x.head<2>(), q.u;
    best_distance = q.distance;
  }
  if (best == saddle.u) return false;
  *out = SolveSurfaceSurface(f, pose_f, g, pose_g, best, kContinuation, out_eval);
  if (out->status != ExtremalStatus::kConverged || !(out->alignment < 0.0)) return false;
  const RelativeCurvature k = RelativeCurvatureOf(*out_eval);
  return k.valid && !k.crossing;
}

}  // namespace tangent::contact
