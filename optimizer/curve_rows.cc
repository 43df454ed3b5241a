#include "optimizer/curve_rows.h"

#include "contact/contact_jacobian.h"
#include "optimizer/contacts.h"

namespace tangent::optimizer::internal {

Eigen::Vector3d CurveRowDirection(const contact::CurveSurfaceExtremum& x) {
  const bool bound = x.at_bound[0] || x.at_bound[1] || x.at_bound[2];
  const Eigen::Vector3d d = x.p_g - x.p_f;  // E − G (the solver's g is the curve)
  if (bound && d.norm() > 0.0) return (x.beta < 0.0 ? -1.0 : 1.0) * d.normalized();
  return x.R_WCf.col(2);
}

bool CurveCurvature(const nurbs::CurvePoint<3>& c, double* kappa) {
  const double speed = c.C1.norm();
  if (!(speed > 0.0)) return false;
  *kappa = c.C1.cross(c.C2).norm() / (speed * speed * speed);
  return true;
}

bool CurveRowReach(const contact::CurveSurfaceEval& e, const contact::CurveSurfaceExtremum& x,
                   Eigen::Vector3d* p, double* reach) {
  double kappa = 0.0;
  if (x.status != contact::ExtremalStatus::kConverged || !CurveCurvature(e.g.world, &kappa)) {
    return false;
  }
  *p = 0.5 * (x.p_f + x.p_g);
  *reach = ContactReach(x.beta, kappa);
  return std::isfinite(*reach);
}

void CurveRowJacobian(const contact::CurveSurfaceEval& e, const Eigen::Vector3d& n,
                      const contact::BodyPose& pa, const contact::BodyPose& pb,
                      Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) {
  J_a = n.transpose() * contact::PointJacobian(pa, e.g.body.C);
  J_b = -n.transpose() * contact::PointJacobian(pb, e.f.body.S);
}

void AddCurveRowHessian(const contact::CurveSurfaceEval& e, const contact::CurveSurfaceExtremum& x,
                        const Eigen::Vector3d& n, const contact::BodyPose& pa,
                        const contact::BodyPose& pb, double w, TermHessian* h) {
  if (x.at_bound[0] || x.at_bound[1] || x.at_bound[2]) return;
  contact::Matrix3x14 solver_q;  // (s, t, τ) over (q_b, q_a), the solver's order
  if (!contact::CurveSurfaceJacobianImplicit(e, pb, pa, &solver_q)) solver_q.setZero();
  contact::Matrix3x14 x_q;  // over (q_a, q_b)
  x_q << solver_q.rightCols<7>(), solver_q.leftCols<7>();
  Eigen::Matrix<double, 3, 14> P;
  P << contact::PointJacobian(pa, e.g.body.C), -contact::PointJacobian(pb, e.f.body.S);
  Eigen::Matrix<double, 3, 14> n_q = Eigen::Matrix<double, 3, 14>::Zero();
  n_q.rightCols<7>() = contact::DirectionJacobian(pb, pb.R_WB.transpose() * n);
  n_q += UnitNormalPartial(e.f.N_W, e.f.N_W_u) * x_q.row(0) +
         UnitNormalPartial(e.f.N_W, e.f.N_W_v) * x_q.row(1);
  Eigen::Matrix<double, 14, 14> H = P.transpose().lazyProduct(n_q);  // (as contacts.cc)
  Eigen::Matrix<double, 1, 14> V_E = Eigen::Matrix<double, 1, 14>::Zero();
  Eigen::Matrix<double, 2, 14> V_G = Eigen::Matrix<double, 2, 14>::Zero();
  V_E.leftCols<7>() = n.transpose() * contact::DirectionJacobian(pa, e.g.body.C1);
  V_G.block<1, 7>(0, 7) = n.transpose() * contact::DirectionJacobian(pb, e.f.body.S_u);
  V_G.block<1, 7>(1, 7) = n.transpose() * contact::DirectionJacobian(pb, e.f.body.S_v);
  H.noalias() += V_E.transpose().lazyProduct(x_q.row(2));
  H.noalias() -= V_G.transpose().lazyProduct(x_q.topRows<2>());
  Split(H, w, h);
  h->W_a.noalias() += (w * n) * e.g.body.C.transpose();
  h->W_b.noalias() -= (w * n) * e.f.body.S.transpose();
}

}  // namespace tangent::optimizer::internal
