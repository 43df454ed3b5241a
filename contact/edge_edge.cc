#include "contact/edge_edge.h"

#include <algorithm>
#include <cmath>

#include "contact/rigid.h"
#include "contact/solve_on_box.h"

namespace tangent::contact {

void EvaluateCurveCurve(const BodyCurve& a, const BodyPose& pose_a, const BodyCurve& b,
                        const BodyPose& pose_b, const Eigen::Vector2d& x, int* span_a,
                        nurbs::SpanHint* hint_a, int* span_b, nurbs::SpanHint* hint_b,
                        CurveCurveEval* out) {
  EvaluatePlaced(a, pose_a, x[0], span_a, hint_a, &out->a);
  EvaluatePlaced(b, pose_b, x[1], span_b, hint_b, &out->b);
  const nurbs::CurvePoint<3>& A = out->a.world;
  const nurbs::CurvePoint<3>& B = out->b.world;
  out->d = A.C - B.C;
  out->grad << out->d.dot(A.C1), -out->d.dot(B.C1);
  out->hess << A.C1.squaredNorm() + out->d.dot(A.C2), -A.C1.dot(B.C1), -A.C1.dot(B.C1),
      B.C1.squaredNorm() - out->d.dot(B.C2);
}

CurveCurveExtremum SolveCurveCurve(const BodyCurve& a, const BodyPose& pose_a, const BodyCurve& b,
                                   const BodyPose& pose_b, const Eigen::Vector2d& seed,
                                   const ExtremalOptions& options, CurveCurveEval* at_solution) {
  CurveCurveExtremum out;
  const Eigen::Vector2d lo(a.domain_begin(), b.domain_begin());
  const Eigen::Vector2d hi(a.domain_end(), b.domain_end());
  if (!seed.allFinite() || !pose_a.q.allFinite() || !pose_b.q.allFinite()) {
    out.x = 0.5 * (lo + hi);
    out.status = ExtremalStatus::kInvalidInput;
    return out;
  }
  int span_a = 0, span_b = 0;
  nurbs::SpanHint hint_a, hint_b;
  CurveCurveEval e;
  // The gradient is the interior system too: its Jacobian (the Hessian) is regular at contact.
  auto eval = [&](const Eigen::Vector2d& x, internal::NewtonSystem<2>* s) {
    EvaluateCurveCurve(a, pose_a, b, pose_b, x, &span_a, &hint_a, &span_b, &hint_b, &e);
    s->value = 0.5 * e.d.squaredNorm();
    s->F = e.grad;
    s->J = e.hess;
    s->grad = e.grad;
    s->hess = e.hess;
    s->classify_scale = std::max(e.a.world.C1.squaredNorm(), e.b.world.C1.squaredNorm());
  };
  auto opt = internal::BoxOptionsOf<2>(options);
  opt.periodic = {a.periodic(), b.periodic()};
  auto no_pole = [](const Eigen::Vector2d&, Eigen::Vector2d*) {
    return internal::PoleAction::kNone;
  };
  internal::NewtonSystem<2> sys;
  const internal::BoxNewtonResult<2> r =
      internal::SolveOnBox<2>(eval, no_pole, seed, lo, hi, opt, options.seek, &sys);
  out.x = r.x;
  out.p_a = e.a.world.C;
  out.p_b = e.b.world.C;
  out.distance = e.d.norm();
  out.at_bound = r.active;
  out.iterations = r.iterations;
  out.status = internal::StatusOf(r);
  out.kind = internal::KindAt<2>(r, sys, lo, hi);
  if (at_solution) *at_solution = e;
  return out;
}

namespace {

// ∂d/∂q at fixed (s, t) (3 x 14) and the curves' tangents' ∂a'/∂q_A, ∂b'/∂q_B (3 x 7 each).
struct PoseDerivatives {
  Matrix3x14 d_q;
  Matrix37d a1_q, b1_q;
};
PoseDerivatives Derivatives(const CurveCurveEval& e, const BodyPose& pose_a,
                            const BodyPose& pose_b) {
  PoseDerivatives p;
  p.d_q << PointJacobian(pose_a, e.a.body.C), -PointJacobian(pose_b, e.b.body.C);
  p.a1_q = DirectionJacobian(pose_a, e.a.body.C1);
  p.b1_q = DirectionJacobian(pose_b, e.b.body.C1);
  return p;
}

}  // namespace

bool CurveCurveJacobian(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                        Matrix2x14* x_q) {
  const PoseDerivatives p = Derivatives(e, pose_a, pose_b);
  const Eigen::Vector3d& a1 = e.a.world.C1;
  const Eigen::Vector3d& b1 = e.b.world.C1;
  Matrix2x14 grad_q;
  grad_q.row(0) = a1.transpose() * p.d_q;
  grad_q.row(0).leftCols<7>() += e.d.transpose() * p.a1_q;
  grad_q.row(1) = -b1.transpose() * p.d_q;
  grad_q.row(1).rightCols<7>() -= e.d.transpose() * p.b1_q;
  const auto lu = internal::Factor<2>(e.hess);
  double rcond = 0.0;
  const double scale = std::max(a1.squaredNorm(), b1.squaredNorm());
  if (internal::IsSingular<2>(lu, scale, &rcond)) return false;
  *x_q = -internal::SolveColumns<2, 14>(lu, grad_q);
  return true;
}

Row14 CurveCurveDistanceGradient(const CurveCurveEval& e, const BodyPose& pose_a,
                                 const BodyPose& pose_b) {
  const Eigen::Vector3d n = e.d.normalized();
  return n.transpose() * Derivatives(e, pose_a, pose_b).d_q;
}

namespace {

// ∂(n·∂d/∂q)/∂q along the extremum for a direction n whose total derivative is n_q: the one
// formula of |d|'s Hessian (n = d/|d|) and the signed row's (n = ν).
Matrix14d RowHessian(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                     const PoseDerivatives& p, const Matrix2x14& x_q, const Eigen::Vector3d& n,
                     const Matrix3x14& n_q) {
  Matrix14d H = p.d_q.transpose() * n_q;  // H(i, j) = ∂(gradient_i)/∂q_j
  // n·∂²d/∂q²: each body's rotation curvature of its point (positions enter linearly).
  H.block<4, 4>(3, 3) += RotateHessian(pose_a.q.tail<4>(), e.a.body.C, n);
  H.block<4, 4>(10, 10) -= RotateHessian(pose_b.q.tail<4>(), e.b.body.C, n);
  // The point Jacobians' own change with the parameters, times the parameters' motion.
  Row14 v_s = Row14::Zero(), v_t = Row14::Zero();
  v_s.leftCols<7>() = n.transpose() * p.a1_q;
  v_t.rightCols<7>() = -n.transpose() * p.b1_q;
  H += v_s.transpose() * x_q.row(0) + v_t.transpose() * x_q.row(1);
  return H;
}

}  // namespace

Matrix14d CurveCurveDistanceHessian(const CurveCurveEval& e, const BodyPose& pose_a,
                                    const BodyPose& pose_b, const Matrix2x14& x_q) {
  const PoseDerivatives p = Derivatives(e, pose_a, pose_b);
  const double len = e.d.norm();
  const Eigen::Vector3d n = e.d / len;
  const Matrix3x14 D = p.d_q + e.a.world.C1 * x_q.row(0) - e.b.world.C1 * x_q.row(1);
  const Matrix3x14 n_q = (Eigen::Matrix3d::Identity() - n * n.transpose()) * D / len;
  return RowHessian(e, pose_a, pose_b, p, x_q, n, n_q);
}

bool CommonNormal(const CurveCurveEval& e, double sign, Eigen::Vector3d* nu) {
  const Eigen::Vector3d& a1 = e.a.world.C1;
  const Eigen::Vector3d& b1 = e.b.world.C1;
  const Eigen::Vector3d c = a1.cross(b1);
  const double len = c.norm();
  if (!(len > 1e-9 * a1.norm() * b1.norm())) return false;
  *nu = (sign / len) * c;
  return true;
}

Row14 EdgeEdgeGradient(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                       const Eigen::Vector3d& nu) {
  return nu.transpose() * Derivatives(e, pose_a, pose_b).d_q;
}

Matrix14d EdgeEdgeHessian(const CurveCurveEval& e, const BodyPose& pose_a, const BodyPose& pose_b,
                          const Matrix2x14& x_q, const Eigen::Vector3d& nu) {
  const PoseDerivatives p = Derivatives(e, pose_a, pose_b);
  const Eigen::Vector3d& a1 = e.a.world.C1;
  const Eigen::Vector3d& b1 = e.b.world.C1;
  // The tangents' total derivatives along the extremum (each body's own block, and the
  // parameters' motion), then the cross product's: Ȧ' × b' + a' × Ḃ'.
  Matrix3x14 A1 = e.a.world.C2 * x_q.row(0);
  A1.leftCols<7>() += p.a1_q;
  Matrix3x14 B1 = e.b.world.C2 * x_q.row(1);
  B1.rightCols<7>() += p.b1_q;
  Matrix3x14 c_q;
  for (int j = 0; j < 14; ++j) {
    c_q.col(j) = Eigen::Vector3d(A1.col(j)).cross(b1) + a1.cross(Eigen::Vector3d(B1.col(j)));
  }
  // ν = σ c/|c|: its derivative is σ (I − ĉĉᵀ) ċ/|c|, and σ ĉ = ν, so the sign rides on ċ.
  const Eigen::Vector3d c = a1.cross(b1);
  const double sign = nu.dot(c) >= 0.0 ? 1.0 : -1.0;
  const Matrix3x14 n_q =
      (sign / c.norm()) * ((Eigen::Matrix3d::Identity() - nu * nu.transpose()) * c_q);
  return RowHessian(e, pose_a, pose_b, p, x_q, nu, n_q);
}

}  // namespace tangent::contact
