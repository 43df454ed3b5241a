#include "contact/placed.h"

namespace tangent::contact {

BodyPose BodyPose::FromCoordinates(const Vector7d& q) {
  BodyPose pose;
  pose.q = q;
  const Eigen::Vector4d Q = q.tail<4>();
  pose.R = RotationMatrix(Q);
  // Normalized map: w_W = R(Q̂) G(Q̂) Q̇ / |Q| (G(Q̂) Q̂ = 0, so the projector drops out).
  const double norm = Q.norm();
  pose.omega_map = pose.R * GBody(Q / norm) / norm;
  return pose;
}

void EvaluatePlaced(const nurbs::NurbsSurface& surface, const BodyPose& pose, double u, double v,
                    nurbs::SpanHint* hint, PlacedSurfacePoint* out) {
  surface.Evaluate<2>(u, v, hint, &out->body);
  const nurbs::SurfacePoint& b = out->body;
  nurbs::SurfacePoint& w = out->world;
  w.S = pose.Point(b.S);
  w.S_u = pose.R * b.S_u;
  w.S_v = pose.R * b.S_v;
  w.S_uu = pose.R * b.S_uu;
  w.S_uv = pose.R * b.S_uv;
  w.S_vv = pose.R * b.S_vv;
  out->N = w.S_u.cross(w.S_v);
  out->N_u = w.S_uu.cross(w.S_v) + w.S_u.cross(w.S_uv);
  out->N_v = w.S_uv.cross(w.S_v) + w.S_u.cross(w.S_vv);
}

double BodyCurve::domain_begin() const {
  return space_ ? space_->knots().domain_begin() : domain_->knots().domain_begin();
}
double BodyCurve::domain_end() const {
  return space_ ? space_->knots().domain_end() : domain_->knots().domain_end();
}

nurbs::CurvePoint<3> BodyCurve::Evaluate(double tau, int* span_hint,
                                          nurbs::SpanHint* surface_hint) const {
  nurbs::CurvePoint<3> out;
  if (space_) {
    space_->Evaluate(tau, 2, span_hint, &out);
    return out;
  }
  nurbs::CurvePoint<2> c;
  domain_->Evaluate(tau, 2, span_hint, &c);
  nurbs::SurfacePoint s;
  surface_->Evaluate<2>(c.C.x(), c.C.y(), surface_hint, &s);
  const double a = c.C1.x(), b = c.C1.y();
  out.C = s.S;
  out.C1 = s.S_u * a + s.S_v * b;
  out.C2 = s.S_uu * (a * a) + 2.0 * s.S_uv * (a * b) + s.S_vv * (b * b) + s.S_u * c.C2.x() +
           s.S_v * c.C2.y();
  return out;
}

void EvaluatePlaced(const BodyCurve& curve, const BodyPose& pose, double tau, int* span_hint,
                    nurbs::SpanHint* surface_hint, PlacedCurvePoint* out) {
  out->body = curve.Evaluate(tau, span_hint, surface_hint);
  out->world.C = pose.Point(out->body.C);
  out->world.C1 = pose.R * out->body.C1;
  out->world.C2 = pose.R * out->body.C2;
}

Matrix37d PointJacobian(const BodyPose& pose, const Eigen::Vector3d& p_B) {
  Matrix37d j;
  j.leftCols<3>().setIdentity();
  j.rightCols<4>() = RotateDerivative(pose.q.tail<4>(), p_B);
  return j;
}

Matrix37d DirectionJacobian(const BodyPose& pose, const Eigen::Vector3d& a_B) {
  Matrix37d j;
  j.leftCols<3>().setZero();
  j.rightCols<4>() = RotateDerivative(pose.q.tail<4>(), a_B);
  return j;
}

}  // namespace tangent::contact
