#include "contact/placed.h"

#include "contact/rigid.h"

namespace tangent::contact {

BodyPose BodyPose::FromCoordinates(const Vector7d& q) {
  BodyPose pose;
  pose.q = q;
  // Written out (this runs twice per servo step): R of the unit quaternion (w, x, y, z) = Q/|Q|,
  // and the normalized map w_W = R(Q̂) G(Q̂) Q̇/|Q| = 2 E(Q̂) Q̇/|Q| with the world-frame rate
  // operator E(Q̂) = [−x w −z y; −y z w −x; −z −y x w] (G(Q̂) Q̂ = 0, so no projector is needed).
  const double norm = q.tail<4>().norm();
  const double inv = 1.0 / norm;
  const double w = q[3] * inv, x = q[4] * inv, y = q[5] * inv, z = q[6] * inv;
  pose.R_WB << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),           //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  const double s = 2.0 * inv;
  pose.omega_map << -x * s, w * s, -z * s, y * s,  //
      -y * s, z * s, w * s, -x * s,                //
      -z * s, -y * s, x * s, w * s;
  return pose;
}

void EvaluatePlaced(const nurbs::NurbsSurface& surface, const BodyPose& pose, double u, double v,
                    nurbs::SpanHint* hint, PlacedSurfacePoint* out) {
  surface.Evaluate<2>(u, v, hint, &out->body);
  PlaceBody(pose, out);
  out->pole = nurbs::IsDegenerate(out->body);
  out->charted = false;
  if (out->pole) out->n_W_limit = pose.R_WB * nurbs::UnitNormal(surface, u, v, out->body);
}

void PlaceBody(const BodyPose& pose, PlacedSurfacePoint* out) {
  const nurbs::SurfacePoint& b = out->body;
  nurbs::SurfacePoint& w = out->world;
  w.S = pose.Point(b.S);
  w.S_u = pose.R_WB * b.S_u;
  w.S_v = pose.R_WB * b.S_v;
  w.S_uu = pose.R_WB * b.S_uu;
  w.S_uv = pose.R_WB * b.S_uv;
  w.S_vv = pose.R_WB * b.S_vv;
  out->N_W = w.S_u.cross(w.S_v);
  out->N_W_u = w.S_uu.cross(w.S_v) + w.S_u.cross(w.S_uv);
  out->N_W_v = w.S_uv.cross(w.S_v) + w.S_u.cross(w.S_vv);
}

double BodyCurve::domain_begin() const {
  if (space_) return space_->knots().domain_begin();
  if (iso_fixed_ >= 0) {
    return (iso_fixed_ == 0 ? surface_->knots_v() : surface_->knots_u()).domain_begin();
  }
  return domain_->knots().domain_begin();
}
double BodyCurve::domain_end() const {
  if (space_) return space_->knots().domain_end();
  if (iso_fixed_ >= 0) {
    return (iso_fixed_ == 0 ? surface_->knots_v() : surface_->knots_u()).domain_end();
  }
  return domain_->knots().domain_end();
}

nurbs::CurvePoint<3> BodyCurve::Evaluate(double tau, int* span_hint,
                                         nurbs::SpanHint* surface_hint) const {
  nurbs::CurvePoint<3> out;
  if (space_) {
    space_->Evaluate(tau, 2, span_hint, &out);
    return out;
  }
  nurbs::SurfacePoint s;
  if (iso_fixed_ >= 0) {  // S(value, τ), the line along v; or S(τ, value), along u
    const bool along_v = iso_fixed_ == 0;
    surface_->Evaluate<2>(along_v ? iso_value_ : tau, along_v ? tau : iso_value_, surface_hint, &s);
    out.C = s.S;
    out.C1 = along_v ? s.S_v : s.S_u;
    out.C2 = along_v ? s.S_vv : s.S_uu;
    return out;
  }
  nurbs::CurvePoint<2> c;
  domain_->Evaluate(tau, 2, span_hint, &c);
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
  out->world.C1 = pose.R_WB * out->body.C1;
  out->world.C2 = pose.R_WB * out->body.C2;
}

Eigen::Matrix3d ContactFrame(const PlacedSurfacePoint& p) {
  Eigen::Matrix3d r;
  const Eigen::Vector3d n = p.unit_normal();
  r.col(2) = n;
  if (!p.pole) {
    r.col(0) = p.world.S_u.normalized();
  } else {
    const Eigen::Vector3d& t =
        p.world.S_u.squaredNorm() >= p.world.S_v.squaredNorm() ? p.world.S_u : p.world.S_v;
    Eigen::Vector3d x = t - t.dot(n) * n;
    if (!(x.norm() > 0.0)) x = n.unitOrthogonal();  // both partials vanished
    r.col(0) = x.normalized();
  }
  r.col(1) = r.col(2).cross(r.col(0));
  return r;
}

Matrix37d PointJacobian(const BodyPose& pose, const Eigen::Vector3d& p_B) {
  Matrix37d j;
  j.leftCols<3>().setIdentity();
  // d(R v)/dt = ω × (R v) = −[R v]× omega_map Q̇: the same derivative as RotateDerivative, from
  // the map the pose already holds.
  j.rightCols<4>().noalias() = -Skew(pose.R_WB * p_B) * pose.omega_map;
  return j;
}

Matrix37d DirectionJacobian(const BodyPose& pose, const Eigen::Vector3d& a_B) {
  Matrix37d j;
  j.leftCols<3>().setZero();
  j.rightCols<4>().noalias() = -Skew(pose.R_WB * a_B) * pose.omega_map;
  return j;
}

}  // namespace tangent::contact
