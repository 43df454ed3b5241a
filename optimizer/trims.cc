#include "optimizer/trims.h"

#include "contact/contact_jacobian.h"
#include "nurbs/refinement.h"
#include "optimizer/curve_rows.h"

namespace tangent::optimizer {

namespace {

using Row14 = Eigen::Matrix<double, 1, 14>;

// A quarter turn counter-clockwise in the (u, v) plane: the left normal of a direction.
Eigen::Vector2d Left(const Eigen::Vector2d& x) { return {-x[1], x[0]}; }

}  // namespace

const char* ToString(TrimForm form) {
  switch (form) {
    case TrimForm::kParametric:
      return "parametric";
    case TrimForm::kSameSurface:
      return "same surface";
    case TrimForm::kOtherSurface:
      return "other surface";
  }
  return "?";
}

TrimConstraintTerm::TrimConstraintTerm(TrimForm form, int body_a, const nurbs::NurbsSurface* f,
                                       const nurbs::NurbsCurve2d* curve, int body_b,
                                       const nurbs::NurbsSurface* g,
                                       const Eigen::Vector4d& pair_seed,
                                       const Eigen::Vector3d& edge_seed)
    : form_(form),
      body_a_(body_a),
      body_b_(body_b),
      f_(f),
      curve_(curve),
      g_(g),
      edge_(f, curve),
      pair_seed_(pair_seed),
      edge_seed_(edge_seed) {}

std::string TrimConstraintTerm::name() const {
  return std::string("trim (") + ToString(form_) + ")";
}

std::unique_ptr<TermState> TrimConstraintTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->pair = pair_seed_;
  st->edge = edge_seed_;
  return st;
}

void TrimConstraintTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  if (st->valid && SamePose(pa.q, st->q_a) && SamePose(pb.q, st->q_b)) return;
  // Both extrema followed from their last parameters (the contact's pair: f against g; the
  // edge: g against the curve f(c(τ)), the curve–surface solver's order).
  st->pair_ext = contact::SolveSurfaceSurface(*f_, pa, *g_, pb, st->pair, contact::kContinuation,
                                              &st->pair_eval);
  st->pair = st->pair_ext.u;
  st->edge_ext = contact::SolveCurveSurface(*g_, pb, edge_, pa, st->edge);
  st->edge = st->edge_ext.u;
  nurbs::SpanHint hint_f, hint_g;
  int span = 0;
  contact::EvaluateCurveSurface(*g_, pb, edge_, pa, st->edge, &hint_f, &span, &hint_g,
                                &st->edge_eval);
  st->q_a = pa.q;
  st->q_b = pb.q;
  st->valid = true;
}

void TrimConstraintTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                  Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                  Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  Update(poses, st);
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  // The extrema's parameter Jacobians, columns [q_a, q_b].
  contact::Matrix4x14 pair_q;
  if (!contact::ContactJacobianImplicit(st->pair_eval, pa, pb, &pair_q)) pair_q.setZero();
  contact::Matrix3x14 edge_q;  // (s, t, τ) over [q_b, q_a]
  if (!contact::CurveSurfaceJacobianImplicit(st->edge_eval, pb, pa, &edge_q)) edge_q.setZero();
  Row14 tau_q;
  tau_q << edge_q.block<1, 7>(2, 7), edge_q.block<1, 7>(2, 0);

  const double tau = st->edge[2];
  const nurbs::CurvePoint<2> c = curve_->Evaluate(tau, 2);
  Row14 r_q;
  if (form_ == TrimForm::kParametric) {
    const double len = c.C1.norm();
    const Eigen::Vector2d nu = Left(c.C1) / len;
    const Eigen::Vector2d nu_t = Left(c.C2 / len - c.C1 * (c.C1.dot(c.C2) / (len * len * len)));
    const Eigen::Vector2d delta = st->pair.head<2>() - c.C;
    r[0] = nu.dot(delta);
    r_q = nu[0] * pair_q.row(0) + nu[1] * pair_q.row(1) + delta.dot(nu_t) * tau_q;
  } else {
    // The edge at τ* in f's frame: E, E', E'' and the surface's unit normal and its change.
    int span = 0;
    nurbs::SpanHint hint;
    const nurbs::CurvePoint<3> E = edge_.Evaluate(tau, &span, &hint);
    const nurbs::SurfacePoint s = f_->Evaluate(c.C[0], c.C[1], 2);
    const Eigen::Vector3d N = s.S_u.cross(s.S_v);
    const Eigen::Vector3d N_u = s.S_uu.cross(s.S_v) + s.S_u.cross(s.S_uv);
    const Eigen::Vector3d N_v = s.S_uv.cross(s.S_v) + s.S_u.cross(s.S_vv);
    const Eigen::Vector3d n = N.normalized();
    const Eigen::Vector3d dN = N_u * c.C1[0] + N_v * c.C1[1];
    const Eigen::Vector3d n_t = (dN - n * n.dot(dN)) / N.norm();
    const double len = E.C1.norm();
    const Eigen::Vector3d T = E.C1 / len;
    const Eigen::Vector3d T_t = (E.C2 - T * T.dot(E.C2)) / len;
    const Eigen::Vector3d m = n.cross(T);
    const Eigen::Vector3d m_t = n_t.cross(T) + n.cross(T_t);
    if (form_ == TrimForm::kSameSurface) {
      const nurbs::SurfacePoint& p = st->pair_eval.f.body;
      const Eigen::Vector3d delta = p.S - E.C;
      r[0] = m.dot(delta);
      r_q = m.dot(p.S_u) * pair_q.row(0) + m.dot(p.S_v) * pair_q.row(1) + delta.dot(m_t) * tau_q;
    } else {
      const contact::PlacedSurfacePoint& gp = st->pair_eval.g;
      const Eigen::Vector3d m_W = pa.R_WB * m;
      const Eigen::Vector3d delta = gp.world.S - pa.Point(E.C);
      r[0] = m_W.dot(delta);
      Eigen::Matrix<double, 3, 14> P;  // ∂(g(s_e) − E(τ))/∂q at fixed parameters
      P << -contact::PointJacobian(pa, E.C), contact::PointJacobian(pb, gp.body.S);
      r_q = m_W.transpose() * P + m_W.dot(gp.world.S_u) * pair_q.row(2) +
            m_W.dot(gp.world.S_v) * pair_q.row(3) + delta.dot(pa.R_WB * m_t) * tau_q;
      r_q.head<7>() += delta.transpose() * contact::DirectionJacobian(pa, m);
    }
  }
  J_a = r_q.head<7>();
  J_b = r_q.tail<7>();
}

TrimmedContactTerm::TrimmedContactTerm(int body_a, const nurbs::NurbsSurface* f,
                                       const nurbs::TrimmedDomain* trim, int body_b,
                                       const nurbs::NurbsSurface* g, const Eigen::Vector4d& seed,
                                       const ContactTracking& tracking)
    : body_a_(body_a),
      body_b_(body_b),
      g_(g),
      face_(body_a, f, body_b, g, seed, tracking),
      edges_(std::make_shared<const contact::TrimEdges>(f, trim)) {}

TrimmedContactTerm::TrimmedContactTerm(int body_a, std::shared_ptr<const contact::TrimEdges> edges,
                                       int body_b, const nurbs::NurbsSurface* g,
                                       const Eigen::Vector4d& seed, const ContactTracking& tracking)
    : body_a_(body_a),
      body_b_(body_b),
      g_(g),
      face_(body_a, &edges->surface(), body_b, g, seed, tracking),
      edges_(std::move(edges)) {}

std::unique_ptr<TermState> TrimmedContactTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->face_state = face_.MakeState();
  return st;
}

void TrimmedContactTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  if (st->valid && SamePose(pa.q, st->q_a) && SamePose(pb.q, st->q_b)) return;
  SurfaceContactTerm::State& face = st->face();
  face.active = true;
  face_.Update(poses, &face);
  // The edge is followed from its last extremum while the contact stays on the same loop's
  // edge (contact::MeasureTrimmed), else started at the loop point nearest the face's.
  const bool was_on_edge = st->on_edge;
  const contact::TrimmedMeasure m =
      contact::MeasureTrimmed(*edges_, pa, *g_, pb, face.ext,
                              was_on_edge && st->valid ? &st->edge : nullptr, &st->material);
  st->on_edge = m.on_edge;
  st->reported = face.ext;
  if (st->on_edge) {
    st->edge = m.edge;
    nurbs::SpanHint hint_g, hint_f;
    int span = 0;
    contact::EvaluateCurveSurface(*g_, pb, edges_->Curve(st->edge), pa, st->edge.u, &hint_g, &span,
                                  &hint_f, &st->edge_eval);
    // β = (E − G)·n along g's normal at an interior extremum of g, along the line between the
    // points where the extremum is held on a bound (g's border, a joint of the loop).
    st->reported.beta = m.beta;
    st->reported.p_f = m.p_f;
    st->reported.p_g = m.p_g;
    st->reported.status = m.status;
    st->reported.direction = internal::CurveRowDirection(st->edge.ext);
  }
  st->switches += st->valid && was_on_edge != st->on_edge;
  st->tracked_steps = face.tracked_steps;
  st->solves = face.solves;
  st->lost = face.lost;
  st->jumps = face.jumps;
  st->q_a = pa.q;
  st->q_b = pb.q;
  st->valid = true;
}

void TrimmedContactTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                  Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                  Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) {  // a free slot: far apart, no gradient, nothing evaluated
    InactiveRow(r, J_a, J_b);
    return;
  }
  Update(poses, st);
  if (!st->on_edge) {
    face_.Evaluate(poses, st->face_state.get(), r, J_a, J_b);
    return;
  }
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  r[0] = st->reported.beta;
  internal::CurveRowJacobian(st->edge_eval, st->reported.direction, pa, pb, J_a, J_b);
}

void TrimmedContactTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                            const Eigen::Ref<const Eigen::VectorXd>& w,
                                            TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) return;
  Update(poses, st);
  if (!st->on_edge) {
    face_.AddWeightedHessian(poses, st->face_state.get(), w, h);
    return;
  }
  // The edge: the curve row's Hessian (curve_rows.h) with E = f(c(τ)).
  internal::AddCurveRowHessian(st->edge_eval, st->edge.ext, st->reported.direction,
                               PoseOf(poses, body_a_), PoseOf(poses, body_b_), w[0], h);
}

bool TrimmedContactTerm::Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const {
  const auto* st = static_cast<const State*>(state);
  if (!st->active || !st->valid) return false;
  if (!st->on_edge) return face_.Reach(st->face_state.get(), p, reach);
  return internal::CurveRowReach(st->edge_eval, st->edge.ext, p, reach);
}

std::shared_ptr<TrimConstraintTerm> MakeTrimConstraint(TrimForm form, int body_a,
                                                       const nurbs::NurbsSurface* f,
                                                       const nurbs::NurbsCurve2d* curve, int body_b,
                                                       const nurbs::NurbsSurface* g,
                                                       const Eigen::Vector4d& pair_seed,
                                                       const Eigen::Vector3d& edge_seed) {
  return std::make_shared<TrimConstraintTerm>(form, body_a, f, curve, body_b, g, pair_seed,
                                              edge_seed);
}

}  // namespace tangent::optimizer
