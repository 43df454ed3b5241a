#include "server/line_contacts.h"

#include <algorithm>
#include <cmath>

#include "contact/relative_curvature.h"

namespace tangent::server {

namespace {

// A parameter moved into a knot domain: wrapped round when the surface is periodic in it,
// clamped to the ends otherwise.
double IntoDomain(double x, const nurbs::KnotVector& k, bool periodic) {
  const double a = k.domain_begin(), b = k.domain_end();
  if (periodic) {
    const double w = b - a;
    return a + (x - a - w * std::floor((x - a) / w));
  }
  return std::clamp(x, a, b);
}

}  // namespace

int LineContacts::AddPair(optimizer::Problem* p, int body_f, const nurbs::NurbsSurface* f,
                          int body_g, const nurbs::NurbsSurface* g) {
  Pair pair;
  for (auto& t : pair.term) {
    t = optimizer::MakeSectionContact(body_f, f, body_g, g);
    p->AddInequality(t);
  }
  pairs_.push_back(std::move(pair));
  return static_cast<int>(pairs_.size()) - 1;
}

void LineContacts::Bind(optimizer::Solver* solver) {
  for (Pair& p : pairs_) {
    for (int side = 0; side < 2; ++side) {
      p.state[side] = &solver->data().StateAs<optimizer::SectionContactTerm::State>(*p.term[side]);
      p.state[side]->Deactivate();
    }
  }
}

void LineContacts::BeginPair(int k) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  p.ratio = 1e300;
  p.seen = false;
}

void LineContacts::Consider(int k, const contact::SurfaceSurfaceExtremum& ext,
                            const contact::SurfacePairEval& e) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  p.seen = true;
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(e);
  if (!rc.valid || !(rc.eigenvalues[1] > 0.0)) return;
  const double ratio = rc.eigenvalues[0] / rc.eigenvalues[1];
  if (ratio >= p.ratio) return;
  p.ratio = ratio;
  p.u = ext.u;
  const Eigen::Vector3d& w = rc.min_direction;
  p.step = contact::ParameterStepAlong(e, w);
  // The sections hold the parameter of f the line runs along most (in length on f).
  p.fixed = (p.step[0] * e.f.world.S_u).norm() >= (p.step[1] * e.f.world.S_v).norm() ? 0 : 1;
  // Half their spacing: the tight direction's length scale 1/λ_max, and within half of either
  // surface's radius of curvature along the line (a wire's bend: the sections stay on the arc
  // the contact lies along).
  double h = 1.0 / rc.eigenvalues[1];
  Eigen::Matrix3d K;
  for (const contact::PlacedSurfacePoint* s : {&e.f, &e.g}) {
    if (contact::ShapeOperator(*s, &K)) {
      const double kappa = std::abs(w.dot(K * w));
      if (kappa > 0.0) h = std::min(h, 0.5 / kappa);
    }
  }
  p.h = h;
}

void LineContacts::EndPair(int k) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  p.want = p.seen && p.ratio < (p.line ? options_.leave : options_.enter);
  if (!p.seen && p.line) {
    // No contact of the pair tracked (the global stage re-seeding it): the sections are exact
    // constraints of their own and hold the pair meanwhile, until both are farther apart than
    // their half spacing.
    const double gap = std::min(p.state[0]->ext.beta, p.state[1]->ext.beta);
    if (gap < p.h) return;
  }
  if (!p.want) {
    if (p.line) {
      p.state[0]->Deactivate();
      p.state[1]->Deactivate();
      p.line = false;
    }
    return;
  }
  if (!p.line) {
    Place(&p);
    return;
  }
  // Moved when the contact slides past the middle half between the sections (same held
  // parameter), or the line turned to the other parameter.
  const optimizer::SectionContactTerm::State& a = *p.state[0];
  const optimizer::SectionContactTerm::State& b = *p.state[1];
  const nurbs::NurbsSurface& f = p.term[0]->f();
  const bool periodic = p.fixed == 0 ? f.periodic_u() : f.periodic_v();
  const nurbs::KnotVector& knots = p.fixed == 0 ? f.knots_u() : f.knots_v();
  const double period = knots.domain_end() - knots.domain_begin();
  auto wrap = [&](double d) { return periodic ? d - period * std::round(d / period) : d; };
  const double half = 0.5 * wrap(b.value - a.value);
  const double mid = a.value + half;
  if (a.fixed != p.fixed || std::abs(wrap(p.u[p.fixed] - mid)) > 0.5 * std::abs(half)) Place(&p);
}

void LineContacts::Place(Pair* p) {
  const nurbs::NurbsSurface& f = p->term[0]->f();
  const nurbs::NurbsSurface& g = p->term[0]->g();
  const int run = 1 - p->fixed;
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;
    const Eigen::Vector4d at = p->u + sign * p->h * p->step;
    const double value = p->fixed == 0 ? IntoDomain(at[0], f.knots_u(), f.periodic_u())
                                       : IntoDomain(at[1], f.knots_v(), f.periodic_v());
    const double tau = run == 0 ? IntoDomain(at[0], f.knots_u(), f.periodic_u())
                                : IntoDomain(at[1], f.knots_v(), f.periodic_v());
    const Eigen::Vector3d seed(IntoDomain(at[2], g.knots_u(), g.periodic_u()),
                               IntoDomain(at[3], g.knots_v(), g.periodic_v()), tau);
    p->state[side]->Place(p->fixed, value, seed);
  }
  p->line = true;
  ++placements_;
}

void LineContacts::Clear() {
  for (Pair& p : pairs_) {
    if (!p.line) continue;
    p.state[0]->Deactivate();
    p.state[1]->Deactivate();
    p.line = false;
  }
}

}  // namespace tangent::server
