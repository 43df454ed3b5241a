#include "optimizer/contacts.h"

#include <algorithm>
#include <stdexcept>

#include <Eigen/LU>

#include "contact/box_newton.h"
#include "contact/contact_jacobian.h"
#include "contact/relative_curvature.h"
#include "contact/rigid.h"
#include "optimizer/split_rows.h"

namespace tangent::optimizer {

namespace {

using Matrix37 = Eigen::Matrix<double, 3, 7>;
using Matrix14 = Eigen::Matrix<double, 14, 14>;

}  // namespace

namespace internal {

Eigen::Vector3d UnitNormalPartial(const Eigen::Vector3d& N, const Eigen::Vector3d& N_a) {
  const double len = N.norm();
  const Eigen::Vector3d n = N / len;
  return (N_a - n * n.dot(N_a)) / len;
}

void Split(const Eigen::Matrix<double, 14, 14>& H, double w, TermHessian* h) {
  // The three blocks of ½w(H + Hᵀ) that are stored, without forming the fourth.
  const double s = 0.5 * w;
  h->aa += s * (H.topLeftCorner<7, 7>() + H.topLeftCorner<7, 7>().transpose());
  h->ab += s * (H.topRightCorner<7, 7>() + H.bottomLeftCorner<7, 7>().transpose());
  h->bb += s * (H.bottomRightCorner<7, 7>() + H.bottomRightCorner<7, 7>().transpose());
}

template <int Ka>
void AddPartialsHessian(const contact::BodyPose& pa, const Eigen::Matrix<double, 3, Ka>& partials_a,
                        const Eigen::Matrix<double, Ka, 14>& x_a, const contact::BodyPose& pb,
                        const Eigen::Matrix<double, 3, 2>& partials_b,
                        const Eigen::Matrix<double, 2, 14>& x_b, const Eigen::Vector3d& n,
                        Eigen::Matrix<double, 14, 14>* H) {
  Eigen::Matrix<double, 4, Ka> V_a;  // V_aᵀ's rotational rows
  for (int k = 0; k < Ka; ++k) {
    V_a.col(k) = contact::DirectionGradient(pa, partials_a.col(k), n).transpose();
  }
  Eigen::Matrix<double, 4, 2> V_b;
  for (int k = 0; k < 2; ++k) {
    V_b.col(k) = contact::DirectionGradient(pb, partials_b.col(k), n).transpose();
  }
  // Coefficient-based products (lazyProduct): at these sizes Eigen would otherwise take its
  // blocked GEMM path, whose packing costs more than the product (callgrind on the servo).
  H->middleRows<4>(3) += V_a.lazyProduct(x_a);
  H->middleRows<4>(10) -= V_b.lazyProduct(x_b);
}

template <int Ka>
Eigen::Matrix<double, 14, 14> NormalRowHessian(
    const Eigen::Matrix<double, 3, 14>& P, const contact::BodyPose& pa,
    const Eigen::Matrix<double, 3, Ka>& partials_a, const Eigen::Matrix<double, Ka, 14>& x_a,
    const contact::BodyPose& pb, const contact::PlacedSurfacePoint& b,
    const Eigen::Matrix<double, 2, 14>& x_b, const Eigen::Vector3d& n) {
  // Along b's (s, t): Pᵀ n_s − V_bᵀ's rows and Pᵀ n_t − V_bᵀ's, one product for both.
  Eigen::Matrix<double, 14, 2> X;
  X.col(0).noalias() = P.transpose() * UnitNormalPartial(b.N_W, b.N_W_u);
  X.col(1).noalias() = P.transpose() * UnitNormalPartial(b.N_W, b.N_W_v);
  X.block<4, 1>(10, 0) -= contact::DirectionGradient(pb, b.world.S_u, n).transpose();
  X.block<4, 1>(10, 1) -= contact::DirectionGradient(pb, b.world.S_v, n).transpose();
  Eigen::Matrix<double, 4, Ka> V_a;  // V_aᵀ's rotational rows: along a's parameters
  for (int k = 0; k < Ka; ++k) {
    V_a.col(k) = contact::DirectionGradient(pa, partials_a.col(k), n).transpose();
  }
  // Coefficient-based products (lazyProduct), as in AddPartialsHessian.
  Matrix14 H = X.lazyProduct(x_b);
  H.middleRows<4>(3) += V_a.lazyProduct(x_a);
  const Eigen::Matrix<double, 3, 4> n_Qb = -contact::Skew(n) * pb.omega_map;  // b's frame turning
  H.rightCols<4>() += P.transpose().lazyProduct(n_Qb);
  return H;
}

template void AddPartialsHessian<1>(const contact::BodyPose&, const Eigen::Matrix<double, 3, 1>&,
                                    const Eigen::Matrix<double, 1, 14>&, const contact::BodyPose&,
                                    const Eigen::Matrix<double, 3, 2>&,
                                    const Eigen::Matrix<double, 2, 14>&, const Eigen::Vector3d&,
                                    Matrix14*);
template void AddPartialsHessian<2>(const contact::BodyPose&, const Eigen::Matrix<double, 3, 2>&,
                                    const Eigen::Matrix<double, 2, 14>&, const contact::BodyPose&,
                                    const Eigen::Matrix<double, 3, 2>&,
                                    const Eigen::Matrix<double, 2, 14>&, const Eigen::Vector3d&,
                                    Matrix14*);
template Matrix14 NormalRowHessian<1>(const Eigen::Matrix<double, 3, 14>&, const contact::BodyPose&,
                                      const Eigen::Matrix<double, 3, 1>&,
                                      const Eigen::Matrix<double, 1, 14>&, const contact::BodyPose&,
                                      const contact::PlacedSurfacePoint&,
                                      const Eigen::Matrix<double, 2, 14>&, const Eigen::Vector3d&);
template Matrix14 NormalRowHessian<2>(const Eigen::Matrix<double, 3, 14>&, const contact::BodyPose&,
                                      const Eigen::Matrix<double, 3, 2>&,
                                      const Eigen::Matrix<double, 2, 14>&, const contact::BodyPose&,
                                      const contact::PlacedSurfacePoint&,
                                      const Eigen::Matrix<double, 2, 14>&, const Eigen::Vector3d&);

}  // namespace internal

using internal::Split;
using internal::UnitNormalPartial;

// ---- Surface–surface -----------------------------------------------------------------------

SurfaceContactTerm::SurfaceContactTerm(int body_f, const nurbs::NurbsSurface* f, int body_g,
                                       const nurbs::NurbsSurface* g, const Eigen::Vector4d& seed,
                                       const ContactTracking& tracking)
    : body_f_(body_f), body_g_(body_g), f_(f), g_(g), seed_(seed), tracking_(tracking) {
  if (!f || !g) throw std::invalid_argument("surface contact: null surface");
  if (body_f == body_g) throw std::invalid_argument("surface contact: both surfaces on one body");
  if (!seed.allFinite()) throw std::invalid_argument("surface contact: non-finite seed");
  if (tracking.corrector_steps < 0 || tracking.corrector_steps > 3)
    throw std::invalid_argument("surface contact: corrector_steps must be 0 to 3");
  if (!(tracking.accept_residual >= kTrackedResidual))
    throw std::invalid_argument("surface contact: accept_residual must be at least 1e-12");
}

std::unique_ptr<TermState> SurfaceContactTerm::MakeState() const {
  contact::TrackerOptions options;
  options.corrector_steps = tracking_.corrector_steps;
  auto st = std::make_unique<State>(*f_, *g_, options);
  st->u = seed_;
  st->own_u = seed_;
  return st;
}

void SurfaceContactTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pf = PoseOf(poses, body_f_);
  const BodyPose& pg = PoseOf(poses, body_g_);
  if (st->anchor.Stands(st->valid, pf.q, st->q_f, pg.q, st->q_g)) return;
  bool done = false;
  if (st->tracking) {
    st->track_status = st->tracker.Step(pf.q, pg.q);
    if (st->track_status == contact::TrackStatus::kTracked) {
      st->ext = contact::ExtremumAt(*f_, pf, *g_, pg, st->tracker.u(), tracking_.accept_residual,
                                    &st->eval, &st->tracker.charts());
      done = st->ext.status == contact::ExtremalStatus::kConverged;
    } else if (st->track_status == contact::TrackStatus::kLost) {
      ++st->lost;
    }
  }
  if (done) {
    ++st->tracked_steps;
  } else {
    // From the tracker's point when it has one close by, else from the last parameters.
    const Eigen::Vector4d& start =
        st->tracking && st->track_status == contact::TrackStatus::kTracked ? st->tracker.u()
                                                                           : st->u;
    st->ext =
        contact::SolveSurfaceSurface(*f_, pf, *g_, pg, start, contact::kContinuation, &st->eval);
    ++st->solves;
    // A solve that did not converge, or ended on a singular Newton matrix, says nothing of
    // where this contact went (undecided). Near a pitchfork of the distance (two wires turning
    // towards parallel: a minimum either side of a saddle, a few 1e-3 of a domain apart) Newton
    // stops between them or on the other side's minimum, and taking that point let both rows of
    // a split contact end on one minimum (bench/hooks_turn: the rings apart at 14.5°). A far
    // solve may also have found another extremum of the pair (FoundAnotherExtremum; the held
    // pair is evaluated only after a far solve: the cheap test first). Either way the pair is
    // held at the parameters the solve started from (β = d·n there, continuous in the poses)
    // until the global stage re-finds the contact; an undecided one's tracker goes on from them.
    const bool undecided = st->valid && (st->ext.status == contact::ExtremalStatus::kNotConverged ||
                                         st->ext.status == contact::ExtremalStatus::kSingular);
    bool jumped = false;
    if (undecided || (st->valid && contact::ParameterDistance(*f_, *g_, start, st->ext.u) >
                                       contact::kMaxResolveJump)) {
      contact::SurfacePairEval held_eval;
      const contact::SurfaceSurfaceExtremum at_start =
          contact::ExtremumAt(*f_, pf, *g_, pg, start, kTrackedResidual, &held_eval);
      jumped =
          !undecided && contact::FoundAnotherExtremum(*f_, *g_, start, st->ext, held_eval.d.norm());
      if (undecided || jumped) {
        ++(undecided ? st->undecided : st->jumps);
        st->ext = at_start;
        st->eval = held_eval;
      }
    }
    st->tracking = !jumped &&
                   (undecided || st->ext.status == contact::ExtremalStatus::kConverged) &&
                   st->tracker.Reset(pf.q, pg.q, st->ext.u) == contact::TrackStatus::kTracked;
  }
  // A row of a split pair (a minimum either side of a saddle: keep_off_saddles) that Newton
  // drew onto the saddle, or into the other minimum's basin (the saddle's and the other
  // minimum's basins reach to within a few 1e-3 of its own just past a pitchfork), goes back to
  // its own minimum: the one on the side of own_u, where it last ended on a minimum (held or
  // undecided evaluations may drift across the saddle with the tracker).
  const bool converged = st->ext.status == contact::ExtremalStatus::kConverged;
  if (st->keep_off_saddles && converged) {
    const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(st->eval);
    contact::SurfaceSurfaceExtremum m;
    contact::SurfacePairEval me;
    bool walked = false;
    if (rc.valid && rc.crossing &&
        internal::MinimumToward(*f_, pf, *g_, pg, st->ext, st->eval, rc, st->own_u, &m, &me)) {
      walked = true;
    } else if (rc.valid && !rc.crossing &&
               contact::ParameterDistance(*f_, *g_, st->own_u, st->ext.u) > kHumpCheckStep &&
               internal::MinimumOnOwnSide(*f_, pf, *g_, pg, st->ext, st->own_u, &m, &me)) {
      walked = true;
    }
    if (walked) {
      st->ext = m;
      st->eval = me;
      ++st->walks;
      st->tracking = st->tracker.Reset(pf.q, pg.q, m.u) == contact::TrackStatus::kTracked;
    }
    if (walked || (rc.valid && !rc.crossing)) st->own_u = st->ext.u;
  } else if (converged) {
    st->own_u = st->ext.u;
  }
  st->u = st->ext.u;
  st->q_f = pf.q;
  st->q_g = pg.q;
  st->valid = true;
}

bool SurfaceContactTerm::Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const {
  const auto* st = static_cast<const State*>(state);
  if (!st->active || !st->valid || st->ext.status != contact::ExtremalStatus::kConverged)
    return false;
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(st->eval);
  if (!rc.valid) return false;
  *p = 0.5 * (st->ext.p_f + st->ext.p_g);
  *reach = ContactReach(st->ext.beta, rc.eigenvalues[1]);
  return std::isfinite(*reach);
}

void SurfaceContactTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                  Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                  Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) {  // a free slot: far apart, no gradient, nothing evaluated
    InactiveRow(r, J_a, J_b);
    return;
  }
  Update(poses, st);
  const BodyPose& pf = PoseOf(poses, body_f_);
  const BodyPose& pg = PoseOf(poses, body_g_);
  // β along the direction the extremum measures it: g's normal at an interior extremum, the
  // line between the points at an edge or corner one (where d is not along a normal). Either
  // way ∂β/∂q = n·∂(f − g)/∂q at fixed parameters (the free parameters are stationary).
  const Eigen::Vector3d& n = st->ext.direction;
  r[0] = st->ext.beta;
  // Fixed-size products into fixed-size blocks of the Refs (a product straight into a dynamic
  // Ref takes Eigen's generic path: ~10x the instructions, callgrind).
  J_a.topLeftCorner<1, 7>() = n.transpose() * contact::PointJacobian(pf, st->eval.f.body.S);
  J_b.topLeftCorner<1, 7>() = -n.transpose() * contact::PointJacobian(pg, st->eval.g.body.S);
}

void SurfaceContactTerm::AddBoundaryHessian(const State& st, const BodyPose& pf, const BodyPose& pg,
                                            double w, TermHessian* h) const {
  // An edge or corner extremum: β = |d| signed, n = d/β. The free parameters stay stationary
  // for ½|d|² (the held ones stay on their bounds), so with grad = [d·f_u, d·f_v, −d·g_s,
  // −d·g_t] their motion is u_q = −hess_FF⁻¹ ∂grad_F/∂q, and with D = ∂d/∂q = P + J_u u_q:
  //   ∇²β = Pᵀ n_q + V_fᵀ u_q^f − V_gᵀ u_q^g + n·∂²(f − g)/∂q²|_u,   n_q = (I − nnᵀ) D / β.
  const nurbs::SurfacePoint& a = st.eval.f.world;
  const nurbs::SurfacePoint& b = st.eval.g.world;
  const Eigen::Vector3d& d = st.eval.d;
  const Eigen::Vector3d& n = st.ext.direction;
  Eigen::Matrix<double, 3, 14> P;
  P << contact::PointJacobian(pf, st.eval.f.body.S), -contact::PointJacobian(pg, st.eval.g.body.S);
  Eigen::Matrix<double, 4, 14> G;  // ∂grad/∂q at fixed parameters
  G.row(0) = a.S_u.transpose() * P;
  G.row(1) = a.S_v.transpose() * P;
  G.row(2) = -b.S_u.transpose() * P;
  G.row(3) = -b.S_v.transpose() * P;
  G.block<1, 7>(0, 0) += d.transpose() * contact::DirectionJacobian(pf, st.eval.f.body.S_u);
  G.block<1, 7>(1, 0) += d.transpose() * contact::DirectionJacobian(pf, st.eval.f.body.S_v);
  G.block<1, 7>(2, 7) -= d.transpose() * contact::DirectionJacobian(pg, st.eval.g.body.S_u);
  G.block<1, 7>(3, 7) -= d.transpose() * contact::DirectionJacobian(pg, st.eval.g.body.S_v);
  Eigen::Matrix4d H_ff = st.eval.hess;
  for (int i = 0; i < 4; ++i) {
    if (!st.ext.at_bound[static_cast<size_t>(i)]) continue;
    H_ff.row(i).setZero();
    H_ff.col(i).setZero();
    H_ff(i, i) = 1.0;
    G.row(i).setZero();
  }
  contact::Matrix4x14 u_q = contact::Matrix4x14::Zero();
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(H_ff);
  if (lu.isInvertible()) u_q = -contact::internal::SolveColumns<4, 14>(lu, G);
  Eigen::Matrix<double, 3, 4> J_u;
  J_u << a.S_u, a.S_v, -b.S_u, -b.S_v;
  const double beta =
      std::abs(st.ext.beta) > 1e-12 ? st.ext.beta : (st.ext.beta < 0.0 ? -1e-12 : 1e-12);
  const Eigen::Matrix<double, 3, 14> n_q =
      (Eigen::Matrix3d::Identity() - n * n.transpose()) * (P + J_u * u_q) / beta;
  Matrix14 H = P.transpose().lazyProduct(n_q);  // (see AddPartialsHessian)
  Eigen::Matrix<double, 3, 2> partials_f, partials_g;
  partials_f << a.S_u, a.S_v;
  partials_g << b.S_u, b.S_v;
  internal::AddPartialsHessian<2>(pf, partials_f, u_q.topRows<2>(), pg, partials_g,
                                  u_q.bottomRows<2>(), n, &H);
  Split(H, w, h);
  h->W_a.noalias() += (w * n) * st.eval.f.body.S.transpose();
  h->W_b.noalias() -= (w * n) * st.eval.g.body.S.transpose();
}

void SurfaceContactTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                            const Eigen::Ref<const Eigen::VectorXd>& w,
                                            TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) return;
  Update(poses, st);
  const BodyPose& pf = PoseOf(poses, body_f_);
  const BodyPose& pg = PoseOf(poses, body_g_);
  const Eigen::Vector3d& n = st->ext.direction;
  const bool at_bound =
      std::any_of(st->ext.at_bound.begin(), st->ext.at_bound.end(), [](bool b) { return b; });
  if (at_bound) {
    AddBoundaryHessian(*st, pf, pg, w[0], h);
    return;
  }
  contact::Matrix4x14 u_q;
  const bool regular = contact::ContactJacobianClosedForm(st->eval, pf, pg, &u_q);
  if (!regular) u_q.setZero();
  // ∇²β = Pᵀ n_q + V_fᵀ u_q^f − V_gᵀ u_q^g (internal::NormalRowHessian) + the rotations'
  // curvature (W below), with P = ∂(f − g)/∂q at fixed parameters.
  Eigen::Matrix<double, 3, 14> P;
  P << contact::PointJacobian(pf, st->eval.f.body.S),
      -contact::PointJacobian(pg, st->eval.g.body.S);
  Eigen::Matrix<double, 3, 2> partials_f;
  partials_f << st->eval.f.world.S_u, st->eval.f.world.S_v;
  const Eigen::Matrix<double, 2, 14> u_f = u_q.topRows<2>(), u_g = u_q.bottomRows<2>();
  Split(internal::NormalRowHessian<2>(P, pf, partials_f, u_f, pg, st->eval.g, u_g, n), w[0], h);
  // n·∂²(f − g)/∂q² at fixed parameters: the rotations' curvature.
  h->W_a.noalias() += (w[0] * n) * st->eval.f.body.S.transpose();
  h->W_b.noalias() -= (w[0] * n) * st->eval.g.body.S.transpose();
}

// ---- Point on surface ----------------------------------------------------------------------

PointOnSurfaceTerm::PointOnSurfaceTerm(const Attachment& point, int body_s,
                                       const nurbs::NurbsSurface* surface,
                                       const Eigen::Vector2d& seed)
    : point_(point), body_s_(body_s), s_(surface), seed_(seed) {
  if (!surface) throw std::invalid_argument("point on surface: null surface");
  if (point.body == body_s)
    throw std::invalid_argument("point on surface: point on the surface's body");
  if (!seed.allFinite()) throw std::invalid_argument("point on surface: non-finite seed");
}

std::unique_ptr<TermState> PointOnSurfaceTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->u = seed_;
  return st;
}

void PointOnSurfaceTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pa = PoseOf(poses, point_.body);
  const BodyPose& ps = PoseOf(poses, body_s_);
  if (st->anchor.Stands(st->valid, pa.q, st->q_a, ps.q, st->q_s)) return;
  st->ext = contact::SolvePointSurface(pa.Point(point_.point), *s_, ps, st->u, {}, &st->eval);
  st->u = st->ext.u;
  st->q_a = pa.q;
  st->q_s = ps.q;
  st->valid = true;
}

void PointOnSurfaceTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                  Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                  Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  Update(poses, st);
  const BodyPose& pa = PoseOf(poses, point_.body);
  const BodyPose& ps = PoseOf(poses, body_s_);
  const Eigen::Vector3d n = st->eval.N_W.normalized();
  r[0] = (pa.Point(point_.point) - st->eval.world.S).dot(n);
  J_a = n.transpose() * contact::PointJacobian(pa, point_.point);
  J_b = -n.transpose() * contact::PointJacobian(ps, st->eval.body.S);
}

void PointOnSurfaceTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                            const Eigen::Ref<const Eigen::VectorXd>& w,
                                            TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  Update(poses, st);
  const BodyPose& pa = PoseOf(poses, point_.body);
  const BodyPose& ps = PoseOf(poses, body_s_);
  const nurbs::SurfacePoint& b = st->eval.body;
  const nurbs::SurfacePoint& s = st->eval.world;
  const Eigen::Vector3d n = st->eval.N_W.normalized();
  const Eigen::Vector3d d = pa.Point(point_.point) - s.S;
  Eigen::Matrix<double, 3, 14> P;
  P << contact::PointJacobian(pa, point_.point), -contact::PointJacobian(ps, b.S);
  // u_q from F = [d·S_u, d·S_v] = 0: F_u u_q = −F_q.
  Eigen::Matrix2d F_u;
  F_u << -s.S_u.dot(s.S_u) + d.dot(ps.R_WB * b.S_uu), -s.S_u.dot(s.S_v) + d.dot(ps.R_WB * b.S_uv),
      -s.S_v.dot(s.S_u) + d.dot(ps.R_WB * b.S_uv), -s.S_v.dot(s.S_v) + d.dot(ps.R_WB * b.S_vv);
  Eigen::Matrix<double, 2, 14> F_q;
  F_q.row(0) = s.S_u.transpose() * P;
  F_q.row(1) = s.S_v.transpose() * P;
  F_q.block<1, 7>(0, 7) += d.transpose() * contact::DirectionJacobian(ps, b.S_u);
  F_q.block<1, 7>(1, 7) += d.transpose() * contact::DirectionJacobian(ps, b.S_v);
  Eigen::Matrix<double, 2, 14> u_q = Eigen::Matrix<double, 2, 14>::Zero();
  const double det = F_u.determinant();
  if (std::abs(det) > 1e-12 * F_u.squaredNorm()) u_q = -F_u.inverse() * F_q;
  Eigen::Matrix<double, 3, 14> n_q = Eigen::Matrix<double, 3, 14>::Zero();
  n_q.rightCols<7>() = contact::DirectionJacobian(ps, ps.R_WB.transpose() * n);
  n_q += UnitNormalPartial(st->eval.N_W, st->eval.N_W_u) * u_q.row(0) +
         UnitNormalPartial(st->eval.N_W, st->eval.N_W_v) * u_q.row(1);
  Matrix14 H = P.transpose() * n_q;
  Eigen::Matrix<double, 2, 14> V = Eigen::Matrix<double, 2, 14>::Zero();
  V.block<1, 7>(0, 7) = n.transpose() * contact::DirectionJacobian(ps, b.S_u);
  V.block<1, 7>(1, 7) = n.transpose() * contact::DirectionJacobian(ps, b.S_v);
  H.noalias() -= V.transpose() * u_q;
  Split(H, w[0], h);
  h->W_a.noalias() += (w[0] * n) * point_.point.transpose();
  h->W_b.noalias() -= (w[0] * n) * b.S.transpose();
}

std::shared_ptr<SurfaceContactTerm> MakeSurfaceContact(int body_f, const nurbs::NurbsSurface* f,
                                                       int body_g, const nurbs::NurbsSurface* g,
                                                       const Eigen::Vector4d& seed,
                                                       const ContactTracking& tracking) {
  return std::make_shared<SurfaceContactTerm>(body_f, f, body_g, g, seed, tracking);
}

std::shared_ptr<PointOnSurfaceTerm> MakePointOnSurface(const Attachment& point, int body_s,
                                                       const nurbs::NurbsSurface* surface,
                                                       const Eigen::Vector2d& seed) {
  return std::make_shared<PointOnSurfaceTerm>(point, body_s, surface, seed);
}

}  // namespace tangent::optimizer
