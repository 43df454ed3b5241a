#include "optimizer/sections.h"

#include <stdexcept>

#include "optimizer/curve_rows.h"

namespace tangent::optimizer {

SectionContactTerm::SectionContactTerm(int body_f, const nurbs::NurbsSurface* f, int body_g,
                                       const nurbs::NurbsSurface* g)
    : body_f_(body_f), body_g_(body_g), f_(f), g_(g) {
  if (!f || !g) throw std::invalid_argument("section contact: null surface");
  if (body_f == body_g) throw std::invalid_argument("section contact: both surfaces on one body");
}

std::unique_ptr<TermState> SectionContactTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->u = Eigen::Vector3d::Constant(0.5);
  return st;
}

void SectionContactTerm::Update(const std::vector<BodyPose>& poses, State* st) const {
  const BodyPose& pa = PoseOf(poses, body_f_);
  const BodyPose& pb = PoseOf(poses, body_g_);
  if (st->anchor.Stands(st->valid, pa.q, st->q_a, pb.q, st->q_b)) return;
  const contact::BodyCurve line = contact::BodyCurve::Isoline(f_, st->fixed, st->value);
  // Followed from its last extremum: a section is a local constraint, its neighbourhood is the
  // contact's own (contact::kContinuation).
  st->ext = contact::SolveCurveSurface(*g_, pb, line, pa, st->u, contact::kContinuation);
  ++st->solves;
  st->u = st->ext.u;
  nurbs::SpanHint hint_g, hint_f;
  int span = 0;
  contact::EvaluateCurveSurface(*g_, pb, line, pa, st->u, &hint_g, &span, &hint_f, &st->eval);
  st->direction = internal::CurveRowDirection(st->ext);
  st->q_a = pa.q;
  st->q_b = pb.q;
  st->valid = true;
}

void SectionContactTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                  Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                  Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) {
    InactiveRow(r, J_a, J_b);
    return;
  }
  Update(poses, st);
  r[0] = st->ext.beta - st->margin;
  internal::CurveRowJacobian(st->eval, st->direction, PoseOf(poses, body_f_),
                             PoseOf(poses, body_g_), J_a, J_b);
}

void SectionContactTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                            const Eigen::Ref<const Eigen::VectorXd>& w,
                                            TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  if (!st->active) return;
  Update(poses, st);
  internal::AddCurveRowHessian(st->eval, st->ext, st->direction, PoseOf(poses, body_f_),
                               PoseOf(poses, body_g_), w[0], h);
}

bool SectionContactTerm::Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const {
  const auto* st = static_cast<const State*>(state);
  return st->active && st->valid && internal::CurveRowReach(st->eval, st->ext, p, reach);
}

std::shared_ptr<SectionContactTerm> MakeSectionContact(int body_f, const nurbs::NurbsSurface* f,
                                                       int body_g, const nurbs::NurbsSurface* g) {
  return std::make_shared<SectionContactTerm>(body_f, f, body_g, g);
}

}  // namespace tangent::optimizer
