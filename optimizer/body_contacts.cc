#include "optimizer/body_contacts.h"

#include <stdexcept>
#include <string>
#include <utility>

namespace tangent::optimizer {

ContactFace MakeContactFace(int id, int body, const nurbs::NurbsSurface* surface,
                            const nurbs::TrimmedDomain* trim) {
  if (!surface)
    throw std::invalid_argument("contact face " + std::to_string(id) + ": null surface");
  ContactFace face{id, body, surface, trim, nullptr};
  if (trim) face.edges = std::make_shared<const contact::TrimEdges>(surface, trim);
  return face;
}

BodyContactTerm::BodyContactTerm(std::vector<ContactFace> faces_a, std::vector<ContactFace> faces_b,
                                 const ContactTracking& tracking)
    : body_a_(-1), body_b_(-1), tracking_(tracking) {
  if (faces_a.empty() || faces_b.empty()) {
    throw std::invalid_argument("body contact: each body needs at least one face");
  }
  body_a_ = faces_a.front().body;
  body_b_ = faces_b.front().body;
  if (body_a_ == body_b_) throw std::invalid_argument("body contact: both sides on one body");
  for (auto* side : {&faces_a, &faces_b}) {
    const int body = side == &faces_a ? body_a_ : body_b_;
    for (ContactFace& face : *side) {
      const std::string name = "body contact: face " + std::to_string(face.id);
      if (face.body != body) throw std::invalid_argument(name + " is on another body");
      if (!face.surface) throw std::invalid_argument(name + " has no surface");
      if (face.trim && !face.edges) throw std::invalid_argument(name + " is trimmed without edges");
      if (FaceIndex(face.id) >= 0) throw std::invalid_argument(name + " is given twice");
      faces_.push_back(std::move(face));
    }
  }
}

int BodyContactTerm::FaceIndex(int id) const {
  for (size_t i = 0; i < faces_.size(); ++i) {
    if (faces_[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

std::unique_ptr<TermState> BodyContactTerm::MakeState() const {
  auto st = std::make_unique<State>();
  // Inner terms on body a's first face and body b's last until the first Target(); their states
  // are made here, once, and re-pointed from then on.
  const ContactFace& fa = faces_.front();
  const ContactFace& fb = faces_.back();
  const Eigen::Vector4d seed = Eigen::Vector4d::Constant(0.5);
  st->plain.emplace(fa.body, fa.surface, fb.body, fb.surface, seed, tracking_);
  st->plain_state = st->plain->MakeState();
  auto cut = std::make_unique<TrimmedContactTerm::State>();
  cut->face_state = st->plain->MakeState();
  st->cut_state = std::move(cut);
  return st;
}

bool BodyContactTerm::Target(State* st, int id_x, int id_y) const {
  int x = FaceIndex(id_x), y = FaceIndex(id_y);
  if (x < 0 || y < 0) return false;
  const ContactFace* fx = &faces_[static_cast<size_t>(x)];
  const ContactFace* fy = &faces_[static_cast<size_t>(y)];
  if (fx->body == fy->body) return false;
  // The measured face f: the trimmed one; with both or neither trimmed, the lower id.
  if (fx->id > fy->id) {
    std::swap(x, y);
    std::swap(fx, fy);
  }
  if (!fx->trim && fy->trim) {
    std::swap(x, y);
    std::swap(fx, fy);
  }
  st->f = x;
  st->g = y;
  st->swapped = fx->body != body_a_;
  st->trimmed = fx->trim != nullptr;
  const Eigen::Vector4d seed = Eigen::Vector4d::Constant(0.5);
  // (The inner states stay active: the slot's own state is what a free slot clears.)
  if (st->trimmed) {
    st->cut.emplace(fx->body, fx->edges, fy->body, fy->surface, seed, tracking_,
                    fy->trim ? fy->edges : nullptr);
    static_cast<TrimmedContactTerm::State&>(*st->cut_state).Rebind(*fx->surface, *fy->surface);
  } else {
    st->plain.emplace(fx->body, fx->surface, fy->body, fy->surface, seed, tracking_);
    static_cast<SurfaceContactTerm::State&>(*st->plain_state).Rebind(*fx->surface, *fy->surface);
  }
  return true;
}

void BodyContactTerm::State::SumCounters() {
  const auto& p = static_cast<const ContactSlotState&>(*plain_state);
  const auto& c = static_cast<const ContactSlotState&>(*cut_state);
  tracked_steps = p.tracked_steps + c.tracked_steps;
  solves = p.solves + c.solves;
  lost = p.lost + c.lost;
  jumps = p.jumps + c.jumps;
  form = trimmed ? c.form : contact::TrimmedForm::kFace;
}

void BodyContactTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                               Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                               Eigen::Ref<Eigen::MatrixXd> J_b) const {
  auto* st = static_cast<State*>(state);
  if (!st->active || st->f < 0) {  // a free slot: far apart, no gradient, nothing evaluated
    InactiveRow(r, J_a, J_b);
    return;
  }
  if (st->swapped) {
    st->inner_term().Evaluate(poses, &st->inner(), r, J_b, J_a);
  } else {
    st->inner_term().Evaluate(poses, &st->inner(), r, J_a, J_b);
  }
  st->SumCounters();
}

void BodyContactTerm::AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                                         const Eigen::Ref<const Eigen::VectorXd>& w,
                                         TermHessian* h) const {
  auto* st = static_cast<State*>(state);
  if (!st->active || st->f < 0) return;
  if (!st->swapped) {
    st->inner_term().AddWeightedHessian(poses, &st->inner(), w, h);
    return;
  }
  // The inner term's blocks are over (body b, body a).
  TermHessian inner;
  inner.SetZero();
  st->inner_term().AddWeightedHessian(poses, &st->inner(), w, &inner);
  h->AddSwapped(inner);
}

bool BodyContactTerm::Reach(const TermState* state, Eigen::Vector3d* p, double* reach) const {
  const auto* st = static_cast<const State*>(state);
  return st->active && st->f >= 0 && st->inner_term().Reach(&st->inner(), p, reach);
}

std::shared_ptr<BodyContactTerm> MakeBodyContact(std::vector<ContactFace> faces_a,
                                                 std::vector<ContactFace> faces_b,
                                                 const ContactTracking& tracking) {
  return std::make_shared<BodyContactTerm>(std::move(faces_a), std::move(faces_b), tracking);
}

}  // namespace tangent::optimizer
