#include "server/face_contacts.h"

namespace tangent::server {

int FaceContacts::AddPair(optimizer::Problem* p, int surface_f, int body_f,
                          const nurbs::NurbsSurface* f, const nurbs::FlatQuad& qf, int surface_g,
                          int body_g, const nurbs::NurbsSurface* g, const nurbs::FlatQuad& qg) {
  Pair pair;
  pair.surface_f = surface_f;
  pair.surface_g = surface_g;
  for (int i = 0; i < kCorners; ++i) {
    const bool of_f = i < 4;
    const nurbs::FlatQuad& q = of_f ? qf : qg;
    const nurbs::NurbsSurface* other = of_f ? g : f;
    const size_t c = static_cast<size_t>(i % 4);
    pair.corner_u[i] = q.corners[c];
    pair.seed[i] = (of_f ? qg : qf).middle;
    pair.term[i] = optimizer::MakeCornerContact({of_f ? body_f : body_g, q.points[c]},
                                                of_f ? body_g : body_f, other, pair.seed[i]);
    pair.row[i] = p->inequalities()[static_cast<size_t>(p->AddInequality(pair.term[i]))].row;
  }
  pairs_.push_back(std::move(pair));
  return static_cast<int>(pairs_.size()) - 1;
}

void FaceContacts::Bind(optimizer::Solver* solver) {
  for (Pair& p : pairs_) {
    for (int i = 0; i < kCorners; ++i) {
      p.state[i] = &solver->data().StateAs<optimizer::CornerContactTerm::State>(*p.term[i]);
      p.state[i]->Deactivate();
    }
  }
}

int FaceContacts::Find(int surface_a, int surface_b) const {
  for (size_t k = 0; k < pairs_.size(); ++k) {
    const Pair& p = pairs_[k];
    if ((p.surface_f == surface_a && p.surface_g == surface_b) ||
        (p.surface_f == surface_b && p.surface_g == surface_a)) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

void FaceContacts::Hold(int k) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  if (p.held) return;
  for (int i = 0; i < kCorners; ++i) p.state[i]->Activate(p.seed[i]);
  p.held = true;
}

void FaceContacts::Release(int k) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  for (auto* s : p.state) s->Deactivate();
  p.held = false;
}

void FaceContacts::Follow() {
  for (int k = 0; k < pairs(); ++k) {
    if (held(k) && Lowest(k) < 0) Release(k);
  }
}

int FaceContacts::Lowest(int k) const {
  const Pair& p = pairs_[static_cast<size_t>(k)];
  int best = -1;
  for (int i = 0; i < kCorners; ++i) {
    if (!p.state[i]->over()) continue;
    if (best < 0 || p.state[i]->point.ext.distance < p.state[best]->point.ext.distance) best = i;
  }
  return best;
}

void FaceContacts::Contact(int k, int i, Eigen::Vector4d* u, Eigen::Vector3d* p_f,
                           Eigen::Vector3d* p_g) const {
  const Pair& p = pairs_[static_cast<size_t>(k)];
  const optimizer::CornerContactTerm::State& s = *p.state[i];
  // The corner itself: its closest point on the other face moved out by its distance along that
  // face's normal.
  const Eigen::Vector3d on_other = s.point.ext.p_f;
  const Eigen::Vector3d corner = on_other + s.point.ext.distance * s.point.ext.R_WCf.col(2);
  if (i < 4) {
    *u << p.corner_u[i], s.point.u;
    *p_f = corner;
    *p_g = on_other;
  } else {
    *u << s.point.u, p.corner_u[i];
    *p_f = on_other;
    *p_g = corner;
  }
}

}  // namespace tangent::server
