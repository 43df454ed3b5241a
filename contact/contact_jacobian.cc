#include "contact/contact_jacobian.h"

#include <Eigen/LU>

#include "contact/box_newton.h"

namespace tangent::contact {

namespace {

// Inverse of a 2 x 2 matrix; false when it is singular by the same measure as the solver's:
// |det| against scale², scale defaulting to the largest entry (then |det|/max|m_ij|² is within
// a factor 2 of the reciprocal condition number). A matrix formed as a difference that cancels
// passes the scale of the terms, so an isotropically small result counts as singular too.
bool Inverse2(const Eigen::Matrix2d& m, Eigen::Matrix2d* inv, double scale = 0.0) {
  const double det = m.determinant();
  scale = std::max(scale, m.cwiseAbs().maxCoeff());
  if (!(std::abs(det) > internal::kSingularRcond * scale * scale)) return false;
  const double inv_det = 1.0 / det;  // One division, not four.
  *inv << m(1, 1) * inv_det, -m(0, 1) * inv_det, -m(1, 0) * inv_det, m(0, 0) * inv_det;
  return true;
}

// One surface's contact-frame data used by every closed form: frame axes (world) and the 2 x 2
// blocks E = [x y]ᵀ[S_u S_v] (upper triangular: x ∥ S_u) and F = [x y]ᵀ[n_u n_v] = [x y]ᵀ[N_u
// N_v]/|N| (n_u = (N_u − n(n·N_u))/|N| and x, y ⟂ n).
struct FrameBlocks {
  Eigen::Vector3d x, y, z;
  Eigen::Matrix2d E, F;
  Eigen::Matrix3d frame() const {
    Eigen::Matrix3d r;
    r << x, y, z;
    return r;
  }
};

FrameBlocks MakeFrameBlocks(const PlacedSurfacePoint& p) {
  FrameBlocks b;
  const double su = p.world.S_u.norm();
  const double inv_n = 1.0 / p.N_W.norm();
  b.x = p.world.S_u / su;
  b.z = p.N_W * inv_n;
  b.y = b.z.cross(b.x);
  b.E << su, b.x.dot(p.world.S_v), 0.0, b.y.dot(p.world.S_v);
  b.F << b.x.dot(p.N_W_u) * inv_n, b.x.dot(p.N_W_v) * inv_n, b.y.dot(p.N_W_u) * inv_n,
      b.y.dot(p.N_W_v) * inv_n;
  return b;
}

}  // namespace

bool ContactJacobianImplicit(const SurfacePairEval& e, const BodyPose& pose_f,
                             const BodyPose& pose_g, Matrix4x14* u_q) {
  u_q->setZero();
  const nurbs::SurfacePoint& fb = e.f.body;
  const nurbs::SurfacePoint& gb = e.g.body;
  const nurbs::SurfacePoint& gw = e.g.world;
  // ∂d/∂q = [∂f/∂q_F, −∂g/∂q_G]; ∂g_s/∂q_G, ∂g_t/∂q_G, ∂N_f/∂q_F rotate body-fixed vectors.
  Matrix3x14 d_q;
  d_q << PointJacobian(pose_f, fb.S), -PointJacobian(pose_g, gb.S);
  Matrix3x14 gs_q = Matrix3x14::Zero(), gt_q = Matrix3x14::Zero(), N_q = Matrix3x14::Zero();
  gs_q.rightCols<7>() = DirectionJacobian(pose_g, gb.S_u);
  gt_q.rightCols<7>() = DirectionJacobian(pose_g, gb.S_v);
  N_q.leftCols<7>() = DirectionJacobian(pose_f, fb.S_u.cross(fb.S_v));
  Matrix4x14 F_q;
  F_q.row(0) = gw.S_u.transpose() * d_q + e.d.transpose() * gs_q;
  F_q.row(1) = gw.S_v.transpose() * d_q + e.d.transpose() * gt_q;
  F_q.row(2) = gw.S_u.transpose() * N_q + e.f.N_W.transpose() * gs_q;
  F_q.row(3) = gw.S_v.transpose() * N_q + e.f.N_W.transpose() * gt_q;
  const auto lu = internal::Factor<4>(e.F_u);
  double rcond = 0.0;
  if (internal::IsSingular<4>(lu, 0.0, &rcond)) return false;
  *u_q = -internal::SolveColumns<4, 14>(lu, F_q);
  return true;
}

Matrix4x14 RelativeVelocityMap(const BodyPose& pose_f, const BodyPose& pose_g,
                               const Eigen::Vector3d& p_g, const Eigen::Matrix3d& frame) {
  // v = V_G(p) − V_F(p) with V_B(p) = ṗ_B + w_B × (p − p_B), w_B = omega_map_B Q̇_B;
  // w = w_G − w_F. Then rows x, y of each in the given frame.
  const Eigen::Matrix<double, 2, 3> P = frame.leftCols<2>().transpose();
  Matrix4x14 b;
  b.block<2, 3>(0, 0) = -P;
  b.block<2, 4>(0, 3) = P * Skew(p_g - pose_f.q.head<3>()) * pose_f.omega_map;
  b.block<2, 3>(0, 7) = P;
  b.block<2, 4>(0, 10) = -P * Skew(p_g - pose_g.q.head<3>()) * pose_g.omega_map;
  b.block<2, 3>(2, 0).setZero();
  b.block<2, 4>(2, 3) = -P * pose_f.omega_map;
  b.block<2, 3>(2, 7).setZero();
  b.block<2, 4>(2, 10) = P * pose_g.omega_map;
  return b;
}

bool ContactJacobianClosedForm(const SurfacePairEval& e, const BodyPose& pose_f,
                               const BodyPose& pose_g, Matrix4x14* u_q) {
  const FrameBlocks f = MakeFrameBlocks(e.f);
  const FrameBlocks g = MakeFrameBlocks(e.g);
  Eigen::Matrix2d R;  // Tangent-plane map from f's frame to g's.
  R << g.x.dot(f.x), g.x.dot(f.y), g.y.dot(f.x), g.y.dot(f.y);
  const double beta = e.d.dot(g.z);
  const double sigma = f.z.dot(g.z) < 0 ? -1.0 : 1.0;
  // Blocks of M and the 2 x 2 elimination sequence (pivot on R_θ E_f, regular for any regular f).
  const Eigen::Matrix2d M11 = R * f.E;
  const Eigen::Matrix2d M12 = -(g.E + beta * g.F);
  const Eigen::Matrix2d M21 = R * f.F;
  const Eigen::Matrix2d M22 = -sigma * g.F;
  Eigen::Matrix2d iM11, iH;
  if (!Inverse2(M11, &iM11)) {
    u_q->setZero();
    return false;
  }
  const Eigen::Matrix2d M21iM11 = M21 * iM11;
  const Eigen::Matrix2d schur_term = M21iM11 * M12;
  const Eigen::Matrix2d H = M22 - schur_term;
  // The Schur complement carries the pair's singularity (focal point, continuum), where its two
  // terms cancel, possibly in both directions at once: judge it against their size.
  const double h_scale = std::max(M22.cwiseAbs().maxCoeff(), schur_term.cwiseAbs().maxCoeff());
  if (!Inverse2(H, &iH, h_scale)) {
    u_q->setZero();
    return false;
  }
  // Right-hand side map C: (v_x, v_y, ω_x, ω_y) ↦ [v_xy + β ω_(y,−x); σ ω_(y,−x)],
  // ω_(y,−x) = K ω_xy with K = [0 1; −1 0].
  Eigen::Matrix2d K;
  K << 0, 1, -1, 0;
  Eigen::Matrix<double, 2, 4> C1, C2;
  C1 << Eigen::Matrix2d::Identity(), beta * K;
  C2 << Eigen::Matrix2d::Zero(), sigma * K;
  // u_g = iH (b2 − M21 iM11 b1);  u_f = iM11 (b1 − M12 u_g).
  Eigen::Matrix4d A;
  const Eigen::Matrix<double, 2, 4> Ag = iH * (C2 - M21iM11 * C1);
  A.topRows<2>() = iM11 * (C1 - M12 * Ag);
  A.bottomRows<2>() = Ag;
  // u_q = A B with B = RelativeVelocityMap(...), formed blockwise: with P = [x_g y_g]ᵀ,
  // W = A_v P and Z = A_w P (A_v, A_w the velocity and rotation columns of A),
  //   ∂u/∂p_F = −W,  ∂u/∂p_G = W,  ∂u/∂Q_F = (W[r_F]× − Z) Ω_F,  ∂u/∂Q_G = −(W[r_G]× − Z) Ω_G,
  // r_B = p_g − p_B; row i of W[r]× is W_i × r.
  Eigen::Matrix<double, 2, 3> P;
  P.row(0) = g.x.transpose();
  P.row(1) = g.y.transpose();
  const Eigen::Matrix<double, 4, 3> W = A.leftCols<2>() * P;
  const Eigen::Matrix<double, 4, 3> Z = A.rightCols<2>() * P;
  const Eigen::Vector3d r_f = e.g.world.S - pose_f.q.head<3>();
  const Eigen::Vector3d r_g = e.g.world.S - pose_g.q.head<3>();
  Eigen::Matrix<double, 4, 3> Wf, Wg;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d w = W.row(i).transpose();
    Wf.row(i) = w.cross(r_f).transpose();
    Wg.row(i) = w.cross(r_g).transpose();
  }
  u_q->block<4, 3>(0, 0) = -W;
  u_q->block<4, 4>(0, 3) = (Wf - Z) * pose_f.omega_map;
  u_q->block<4, 3>(0, 7) = W;
  u_q->block<4, 4>(0, 10) = -(Wg - Z) * pose_g.omega_map;
  return true;
}

bool ContactJacobianMontana(const SurfacePairEval& e, const BodyPose& pose_f,
                            const BodyPose& pose_g, Matrix4x14* u_q) {
  u_q->setZero();
  const FrameBlocks f = MakeFrameBlocks(e.f);
  const FrameBlocks g = MakeFrameBlocks(e.g);
  // The formula holds for facing normals only (σ = −1; R below is then a reflection). For
  // same-direction normals it returned true with 150 % error: checked, not only documented.
  if (!(f.z.dot(g.z) < -1.0 + kMontanaFacingTolerance)) return false;
  Eigen::Matrix2d iEf, iEg;
  if (!Inverse2(f.E, &iEf) || !Inverse2(g.E, &iEg)) return false;
  Eigen::Matrix2d R;
  R << g.x.dot(f.x), g.x.dot(f.y), g.y.dot(f.x), g.y.dot(f.y);
  const double beta = e.d.dot(g.z);
  const Eigen::Matrix2d IIf = f.F * iEf, IIg = g.F * iEg;
  const Eigen::Matrix2d IIf_t = R * IIf * R;  // R is a reflection for facing normals: R⁻¹ = R.
  Eigen::Matrix2d m1, m2;
  if (!Inverse2(IIg + IIf_t + beta * IIg * IIf_t, &m1)) return false;
  if (!Inverse2(IIg + IIf_t + beta * IIf_t * IIg, &m2)) return false;
  // [−ω_y; ω_x] = W ω_xy with W = [0 −1; 1 0].
  Eigen::Matrix2d W;
  W << 0, -1, 1, 0;
  Eigen::Matrix4d A;
  A.block<2, 2>(0, 0) = iEf * R * m1 * IIg;
  A.block<2, 2>(0, 2) = iEf * R * m1 * W;
  A.block<2, 2>(2, 0) = -iEg * m2 * IIf_t;
  A.block<2, 2>(2, 2) = iEg * m2 * (Eigen::Matrix2d::Identity() + beta * IIf_t) * W;
  *u_q = A * RelativeVelocityMap(pose_f, pose_g, e.g.world.S, g.frame());
  return true;
}

void PointAndDistanceJacobians(const SurfacePairEval& e, const BodyPose& pose_f,
                               const BodyPose& pose_g, const Matrix4x14& u_q, Matrix3x14* f_q,
                               Matrix3x14* g_q, Row14* beta_q) {
  f_q->setZero();
  g_q->setZero();
  f_q->leftCols<7>() = PointJacobian(pose_f, e.f.body.S);
  g_q->rightCols<7>() = PointJacobian(pose_g, e.g.body.S);
  *f_q += e.f.world.S_u * u_q.row(0) + e.f.world.S_v * u_q.row(1);
  *g_q += e.g.world.S_u * u_q.row(2) + e.g.world.S_v * u_q.row(3);
  *beta_q = e.g.N_W.normalized().transpose() * (*f_q - *g_q);
}

bool CurveSurfaceJacobianImplicit(const CurveSurfaceEval& e, const BodyPose& pose_f,
                                  const BodyPose& pose_g, Matrix3x14* u_q) {
  u_q->setZero();
  const nurbs::SurfacePoint& fb = e.f.body;
  const nurbs::SurfacePoint& fw = e.f.world;
  // F = [d·f_u, d·f_v, N_f·g'] with d = g − f.
  Matrix3x14 d_q;
  d_q << -PointJacobian(pose_f, fb.S), PointJacobian(pose_g, e.g.body.C);
  Matrix3x14 fu_q = Matrix3x14::Zero(), fv_q = Matrix3x14::Zero(), N_q = Matrix3x14::Zero(),
             g1_q = Matrix3x14::Zero();
  fu_q.leftCols<7>() = DirectionJacobian(pose_f, fb.S_u);
  fv_q.leftCols<7>() = DirectionJacobian(pose_f, fb.S_v);
  N_q.leftCols<7>() = DirectionJacobian(pose_f, fb.S_u.cross(fb.S_v));
  g1_q.rightCols<7>() = DirectionJacobian(pose_g, e.g.body.C1);
  Matrix3x14 F_q;
  F_q.row(0) = fw.S_u.transpose() * d_q + e.d.transpose() * fu_q;
  F_q.row(1) = fw.S_v.transpose() * d_q + e.d.transpose() * fv_q;
  F_q.row(2) = e.g.world.C1.transpose() * N_q + e.f.N_W.transpose() * g1_q;
  const auto lu = internal::Factor<3>(e.F_u);
  double rcond = 0.0;
  if (internal::IsSingular<3>(lu, 0.0, &rcond)) return false;
  *u_q = -internal::SolveColumns<3, 14>(lu, F_q);
  return true;
}

bool CurveSurfaceJacobianClosedForm(const CurveSurfaceEval& e, const BodyPose& pose_f,
                                    const BodyPose& pose_g, Matrix3x14* u_q) {
  u_q->setZero();
  const FrameBlocks f = MakeFrameBlocks(e.f);
  const Eigen::Matrix3d frame = f.frame();
  const Eigen::Matrix2d& Ef = f.E;
  const Eigen::Matrix2d& Ff = f.F;
  const Eigen::Matrix<double, 2, 3> P = frame.leftCols<2>().transpose();
  const double beta = e.d.dot(frame.col(2));
  const Eigen::Vector3d& g1 = e.g.world.C1;
  const double g1_len = g1.norm();
  const Eigen::Vector2d T = P * g1 / g1_len;  // Unit tangent in f's tangent plane.
  Eigen::Matrix3d M;
  M.topLeftCorner<2, 2>() = Ef + beta * Ff;
  M.topRightCorner<2, 1>() = -P * g1;
  M.bottomLeftCorner<1, 2>() = T.transpose() * Ff;
  M(2, 2) = frame.col(2).dot(e.g.world.C2) / g1_len;
  const auto lu = internal::Factor<3>(M);
  double rcond = 0.0;
  if (internal::IsSingular<3>(lu, 0.0, &rcond)) return false;
  // B: rows v_x, v_y and T_x ω_y − T_y ω_x of the relative motion at the curve point.
  const Matrix4x14 vw = RelativeVelocityMap(pose_f, pose_g, e.g.world.C, frame);
  Matrix3x14 B;
  B.topRows<2>() = vw.topRows<2>();
  B.row(2) = T.x() * vw.row(3) - T.y() * vw.row(2);
  *u_q = internal::SolveColumns<3, 14>(lu, B);
  return true;
}

}  // namespace tangent::contact
