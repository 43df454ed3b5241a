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
  // (Fixed-size blocks of the Refs: a product into a dynamic Ref takes Eigen's generic path.)
  J_a.topLeftCorner<1, 7>() = n.transpose() * contact::PointJacobian(pa, e.g.body.C);
  J_b.topLeftCorner<1, 7>() = -n.transpose() * contact::PointJacobian(pb, e.f.body.S);
}

void AddCurveRowHessian(const contact::CurveSurfaceEval& e, const contact::CurveSurfaceExtremum& x,
                        const Eigen::Vector3d& n, const contact::BodyPose& pa,
                        const contact::BodyPose& pb, double w, TermHessian* h) {
  if (x.at_bound[0] || x.at_bound[1] || x.at_bound[2]) return;
  contact::Matrix3x14 solver_q;  // (s, t, τ) over (q_b, q_a), the solver's order
  if (!contact::CurveSurfaceJacobianImplicit(e, pb, pa, &solver_q)) solver_q.setZero();
  contact::Matrix3x14 x_q;  // over (q_a, q_b)
  x_q << solver_q.rightCols<7>(), solver_q.leftCols<7>();
  // ∇²β = Pᵀ n_q + V_Eᵀ x_q^τ − V_Gᵀ x_q^(s,t) (NormalRowHessian: the surface pair's form
  // with the curve's one parameter), P = [∂E/∂q_a, −∂G/∂q_b] at fixed parameters.
  Eigen::Matrix<double, 3, 14> P;
  P << contact::PointJacobian(pa, e.g.body.C), -contact::PointJacobian(pb, e.f.body.S);
  const Eigen::Matrix<double, 1, 14> x_tau = x_q.row(2);
  const Eigen::Matrix<double, 2, 14> x_st = x_q.topRows<2>();
  Split(NormalRowHessian<1>(P, pa, e.g.world.C1, x_tau, pb, e.f, x_st, n), w, h);
  h->W_a.noalias() += (w * n) * e.g.body.C.transpose();
  h->W_b.noalias() -= (w * n) * e.f.body.S.transpose();
}

}  // namespace tangent::optimizer::internal
