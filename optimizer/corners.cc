#include "optimizer/corners.h"

namespace tangent::optimizer {

CornerContactTerm::CornerContactTerm(const Attachment& corner, int body_s,
                                     const nurbs::NurbsSurface* surface,
                                     const Eigen::Vector2d& seed)
    : point_(corner, body_s, surface, seed), seed_(seed) {}

std::unique_ptr<TermState> CornerContactTerm::MakeState() const {
  auto st = std::make_unique<State>();
  st->point.u = seed_;
  return st;
}

void CornerContactTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                 Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                 Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  if (st->active) point_.Update(poses, &st->point);
  if (!st->over()) {
    InactiveRow(r, J_a, J_b);
    return;
  }
  point_.Evaluate(poses, &st->point, r, J_a, J_b);
}

void CornerContactTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                           const Eigen::Ref<const Eigen::VectorXd>& w,
                                           TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  if (st->active) point_.Update(poses, &st->point);
  if (!st->over()) return;
  point_.AddWeightedHessian(poses, &st->point, w, h);
}

std::shared_ptr<CornerContactTerm> MakeCornerContact(const Attachment& corner, int body_s,
                                                     const nurbs::NurbsSurface* surface,
                                                     const Eigen::Vector2d& seed) {
  return std::make_shared<CornerContactTerm>(corner, body_s, surface, seed);
}

}  // namespace tangent::optimizer
