#include "optimizer/trims.h"

#include <algorithm>
#include <cmath>

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
  if (st->anchor.Stands(st->valid, pa.q, st->q_a, pb.q, st->q_b)) return;
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
                                       const ContactTracking& tracking,
                                       const nurbs::TrimmedDomain* trim_g)
    : body_a_(body_a),
      body_b_(body_b),
      g_(g),
      face_(body_a, f, body_b, g, seed, tracking),
      edges_(std::make_shared<const contact::TrimEdges>(f, trim)),
      edges_g_(trim_g ? std::make_shared<const contact::TrimEdges>(g, trim_g) : nullptr) {}

TrimmedContactTerm::TrimmedContactTerm(int body_a, std::shared_ptr<const contact::TrimEdges> edges,
                                       int body_b, const nurbs::NurbsSurface* g,
                                       const Eigen::Vector4d& seed, const ContactTracking& tracking,
                                       std::shared_ptr<const contact::TrimEdges> edges_g)
    : body_a_(body_a),
      body_b_(body_b),
      g_(g),
      face_(body_a, &edges->surface(), body_b, g, seed, tracking),
      edges_(std::move(edges)),
      edges_g_(std::move(edges_g)) {}

std::unique_ptr<TermState> TrimmedContactTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->face_state = face_.MakeState();
  return st;
}

void TrimmedContactTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  if (st->anchor.Stands(st->valid, pa.q, st->q_a, pb.q, st->q_b)) return;
  SurfaceContactTerm::State& face = st->face();
  face.active = true;
  // The edges are followed from the last measure while the contact keeps its form and loops
  // (contact::MeasureTrimmedPair), else started at the loop points nearest the face's.
  const contact::TrimmedForm was = st->measure.form;
  // Reseeded at a contact's points (a global-stage event) on two trimmed faces: that contact, in
  // its own form, is the one followed.
  const bool seeded =
      st->seeded && edges_g_ &&
      contact::MeasureTrimmedPairAt(*edges_, pa, *edges_g_, pb, st->reported.u, &st->measure);
  st->seeded = false;
  const bool follow = st->valid || seeded;
  // With both faces trimmed an edge contact is followed, and left, on its own (its
  // multipliers): the faces' extremum, which can wander far off both materials, is solved only
  // when the contact may return to the faces.
  const bool edge_followed = edges_g_ && follow && st->measure.form != contact::TrimmedForm::kFace;
  if (!edge_followed) face_.Update(poses, &face);
  st->measure = contact::MeasureTrimmedPair(
      *edges_, pa, *g_, edges_g_.get(), pb, edge_followed ? nullptr : &face.ext,
      follow ? &st->measure : nullptr, &st->material, &st->material_g);
  if (st->measure.face_wanted) {
    face.Reseed(contact::PointParameters(*edges_, *edges_g_, st->measure, face.ext.u));
    face_.Update(poses, &face);
    st->measure = contact::MeasureTrimmedPair(*edges_, pa, *g_, edges_g_.get(), pb, &face.ext,
                                              &st->measure, &st->material, &st->material_g);
  }
  const contact::TrimmedMeasure& m = st->measure;
  st->on_edge = m.on_edge;
  st->reported = face.ext;
  if (st->on_edge) {
    nurbs::SpanHint hint_g, hint_f;
    int span = 0;
    switch (m.form) {
      case contact::TrimmedForm::kEdgeOfF:
        contact::EvaluateCurveSurface(*g_, pb, edges_->Curve(m.edge), pa, m.edge.u, &hint_g, &span,
                                      &hint_f, &st->edge_eval);
        // β = (E − G)·n along g's normal at an interior extremum of g, along the line between
        // the points where the extremum is held on a bound (g's border, a joint of the loop).
        st->row_direction = internal::CurveRowDirection(m.edge.ext);
        st->reported.direction = st->row_direction;
        break;
      case contact::TrimmedForm::kEdgeOfG:
        // g's edge E on body b against f's face F: the curve row's β = (E − F)·n_f, the same
        // number as (p_f − p_g)·(−n_f).
        contact::EvaluateCurveSurface(edges_->surface(), pa, edges_g_->Curve(m.edge), pb, m.edge.u,
                                      &hint_f, &span, &hint_g, &st->edge_eval);
        st->row_direction = internal::CurveRowDirection(m.edge.ext);
        st->reported.direction = -st->row_direction;
        break;
      case contact::TrimmedForm::kEdgeEdge:  // (evaluated by the solve: m.edge_edge.eval)
        st->reported.direction = m.edge_edge.nu;
        break;
      case contact::TrimmedForm::kFace:
        break;
    }
    if (edges_g_) st->reported.u = contact::PointParameters(*edges_, *edges_g_, m, face.ext.u);
    st->reported.beta = m.beta;
    st->reported.p_f = m.p_f;
    st->reported.p_g = m.p_g;
    st->reported.status = m.status;
  }
  st->switches += st->valid && was != m.form;
  st->form = m.form;
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
  switch (st->measure.form) {
    case contact::TrimmedForm::kEdgeOfF:
      internal::CurveRowJacobian(st->edge_eval, st->row_direction, pa, pb, J_a, J_b);
      break;
    case contact::TrimmedForm::kEdgeOfG:  // the curve on body b, the surface on body a
      internal::CurveRowJacobian(st->edge_eval, st->row_direction, pb, pa, J_b, J_a);
      break;
    default: {  // edge–edge: ∇β = ν·∂(a − b)/∂q at fixed parameters
      const contact::Row14 g =
          contact::EdgeEdgeGradient(st->measure.edge_edge.eval, pa, pb, st->measure.edge_edge.nu);
      J_a = g.head<7>();
      J_b = g.tail<7>();
    }
  }
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
  const BodyPose& pa = PoseOf(poses, body_a_);
  const BodyPose& pb = PoseOf(poses, body_b_);
  const contact::TrimmedMeasure& m = st->measure;
  switch (m.form) {
    case contact::TrimmedForm::kEdgeOfF:  // the curve row's Hessian (curve_rows.h), E = f(c(τ))
      internal::AddCurveRowHessian(st->edge_eval, m.edge.ext, st->row_direction, pa, pb, w[0], h);
      break;
    case contact::TrimmedForm::kEdgeOfG: {  // the same over (body b, body a), blocks swapped
      TermHessian inner;
      inner.SetZero();
      internal::AddCurveRowHessian(st->edge_eval, m.edge.ext, st->row_direction, pb, pa, w[0],
                                   &inner);
      h->AddSwapped(inner);
      break;
    }
    default: {  // edge–edge: exact where both parameters are free (else Gauss–Newton)
      const contact::EdgeEdgeFollow& ee = m.edge_edge;
      contact::Matrix2x14 x_q;
      if (!ee.common_normal || !contact::CurveCurveJacobian(ee.eval, pa, pb, &x_q)) {
        return;
      }
      internal::Split(contact::EdgeEdgeHessian(ee.eval, pa, pb, x_q, ee.nu), w[0], h);
    }
  }
}

bool TrimmedContactTerm::Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const {
  const auto* st = static_cast<const State*>(state);
  if (!st->active || !st->valid) return false;
  if (!st->on_edge) return face_.Reach(st->face_state.get(), p, reach);
  const contact::TrimmedMeasure& m = st->measure;
  if (m.form != contact::TrimmedForm::kEdgeEdge) {
    return internal::CurveRowReach(st->edge_eval, m.edge.ext, p, reach);
  }
  // Two edges: the gap plus a quarter of the tighter edge's radius of curvature.
  double kappa_a = 0.0, kappa_b = 0.0;
  if (m.status != contact::ExtremalStatus::kConverged ||
      !internal::CurveCurvature(m.edge_edge.eval.a.world, &kappa_a) ||
      !internal::CurveCurvature(m.edge_edge.eval.b.world, &kappa_b)) {
    return false;
  }
  const double kappa = std::max(kappa_a, kappa_b);
  *p = 0.5 * (m.p_f + m.p_g);
  *reach = ContactReach(m.beta, kappa);
  return std::isfinite(*reach);
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
