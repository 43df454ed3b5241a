#include "server/line_contacts.h"

#include <algorithm>
#include <cmath>

#include "contact/relative_curvature.h"

namespace tangent::server {

namespace {

const nurbs::KnotVector& Knots(const nurbs::NurbsSurface& s, int i) {
  return i == 0 ? s.knots_u() : s.knots_v();
}
bool Periodic(const nurbs::NurbsSurface& s, int i) {
  return i == 0 ? s.periodic_u() : s.periodic_v();
}

// A side section must read this much nearer than the middle for the sections to move (m): on a
// straight line of minima (a rod in a groove) the three read alike, and a move on their rounding
// differences rocks the part from one end section to the other.
constexpr double kMoveGap = 1e-7;

}  // namespace

bool SectionDip(double below, double middle, double above, double* at) {
  if (!std::isfinite(below) || !std::isfinite(middle) || !std::isfinite(above)) return false;
  // The parabola through (−1, below), (0, middle), (1, above): curvature `curve`, slope `slope`
  // at 0, its lowest point at x = −slope / curve, with the value middle − slope² / (2 curve).
  const double curve = below + above - 2.0 * middle, slope = 0.5 * (above - below);
  if (!(curve > 0.0) || !(std::abs(slope) < curve)) return false;
  if (!(middle - slope * slope / (2.0 * curve) < std::min({below, middle, above}))) return false;
  *at = -slope / curve;
  return true;
}

double LineSpacing(double lambda_min, double lambda_max, double dip) {
  if (!(lambda_max > 0.0)) return INFINITY;
  double h = 1.0 / lambda_max;
  if (lambda_min > 0.0 && dip > 0.0) h = std::min(h, 2.0 * std::sqrt(2.0 * dip / lambda_min));
  return h;
}

int LineContacts::AddPair(optimizer::Problem* p, int body_f, const nurbs::NurbsSurface* f,
                          int body_g, const nurbs::NurbsSurface* g) {
  Pair pair;
  for (int i = 0; i < kSections; ++i) {
    pair.term[i] = optimizer::MakeSectionContact(body_f, f, body_g, g);
    pair.row[i] = p->inequalities()[static_cast<size_t>(p->AddInequality(pair.term[i]))].row;
  }
  pair.probe_data = pair.term[0]->MakeState();
  pair.probe = static_cast<optimizer::SectionContactTerm::State*>(pair.probe_data.get());
  pairs_.push_back(std::move(pair));
  return static_cast<int>(pairs_.size()) - 1;
}

void LineContacts::Bind(optimizer::Solver* solver) {
  for (Pair& p : pairs_) {
    for (int i = 0; i < kSections; ++i) {
      p.state[i] = &solver->data().StateAs<optimizer::SectionContactTerm::State>(*p.term[i]);
      p.state[i]->Deactivate();
    }
  }
}

double LineContacts::Wrap(const Pair& p, double d) const {
  const nurbs::NurbsSurface& f = p.term[0]->f();
  if (!Periodic(f, p.fixed)) return d;
  const double period = Knots(f, p.fixed).domain_end() - Knots(f, p.fixed).domain_begin();
  return d - period * std::round(d / period);
}

bool LineContacts::Enter(int k, const contact::SurfaceSurfaceExtremum& ext,
                         const contact::SurfacePairEval& e) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  if (p.line) return false;
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(e);
  if (!rc.valid || !(rc.eigenvalues[1] > 0.0)) return false;
  if (!(rc.eigenvalues[0] < options_.enter * rc.eigenvalues[1])) return false;
  const Eigen::Vector3d& w = rc.min_direction;
  const Eigen::Vector4d per_metre = contact::ParameterStepAlong(e, w);
  // The sections hold the parameter of f the line runs along most (in length on f).
  p.fixed = (per_metre[0] * e.f.world.S_u).norm() >= (per_metre[1] * e.f.world.S_v).norm() ? 0 : 1;
  if (!(std::abs(per_metre[p.fixed]) > 0.0)) return false;
  // Their spacing: the tight direction's length scale 1/λ_max, close enough that the gap dips at
  // most options_.dip between two of them (LineSpacing), within half of either surface's radius
  // of curvature along the line (a wire's bend: the sections stay on the arc the contact lies
  // along).
  double h = LineSpacing(rc.eigenvalues[0], rc.eigenvalues[1], options_.dip);
  Eigen::Matrix3d K;
  for (const contact::PlacedSurfacePoint* s : {&e.f, &e.g}) {
    if (contact::ShapeOperator(*s, &K)) {
      const double kappa = std::abs(w.dot(K * w));
      if (kappa > 0.0) h = std::min(h, 0.5 / kappa);
    }
  }
  p.h_free = h;
  p.per_metre = per_metre;
  p.step = per_metre / per_metre[p.fixed];
  if (!Fit(&p, ext.u)) return false;
  Place(&p, ext.u);
  for (auto* st : p.state) st->margin = 0.0;
  p.entering = true;
  return true;
}

bool LineContacts::Fit(Pair* p, const Eigen::Vector4d& middle) const {
  // Within both surfaces: the side sections' parameters (f's held one, g's two, moved along the
  // line) stay inside their domains where those end (a rod shorter than its groove: the sections
  // stay on the rod), at 0.9 of the nearer end either way.
  const nurbs::NurbsSurface& f = p->term[0]->f();
  const nurbs::NurbsSurface& g = p->term[0]->g();
  double h = p->h_free;
  for (int i : {p->fixed, 2, 3}) {
    const nurbs::NurbsSurface& s = i < 2 ? f : g;
    const int d = i < 2 ? i : i - 2;
    if (Periodic(s, d) || !(std::abs(p->per_metre[i]) > 0.0)) continue;
    const double room =
        std::min(middle[i] - Knots(s, d).domain_begin(), Knots(s, d).domain_end() - middle[i]);
    h = std::min(h, 0.9 * room / std::abs(p->per_metre[i]));
  }
  if (!(h > 0.0)) return false;  // at an end of the line: nothing either side
  p->h = h;
  p->spacing = h * std::abs(p->per_metre[p->fixed]);
  return true;
}

void LineContacts::Place(Pair* p, const Eigen::Vector4d& middle) {
  for (int i = 0; i < kSections; ++i) {
    const Eigen::Vector4d at = contact::IntoPairDomain(p->term[0]->f(), p->term[0]->g(),
                                                       middle + kOffset[i] * p->spacing * p->step);
    p->state[i]->Place(p->fixed, at[p->fixed], Eigen::Vector3d(at[2], at[3], at[1 - p->fixed]));
  }
  p->line = true;
  ++placements_;
}

Eigen::Vector4d LineContacts::MiddleU(int k) const {
  const Pair& p = pairs_[static_cast<size_t>(k)];
  const optimizer::SectionContactTerm::State& m = *p.state[0];
  Eigen::Vector4d u;
  u[p.fixed] = m.value;
  u[1 - p.fixed] = m.u[2];
  u.tail<2>() = m.u.head<2>();
  return u;
}

bool LineContacts::Covers(int k, const Eigen::Vector4d& u) const {
  const Pair& p = pairs_[static_cast<size_t>(k)];
  return p.line && std::abs(Wrap(p, u[p.fixed] - p.state[0]->value)) <= 1.5 * p.spacing;
}

void LineContacts::Leave(int k, Eigen::Vector4d* u) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  *u = MiddleU(k);
  for (auto* s : p.state) s->Deactivate();
  p.line = false;
  p.entering = false;
}

LineContacts::Next LineContacts::Follow(int k, const std::vector<contact::BodyPose>& poses,
                                        Eigen::Vector4d* u) {
  Pair& p = pairs_[static_cast<size_t>(k)];
  p.entering = false;
  double beta[kSections];
  for (int i = 0; i < kSections; ++i) {
    // (Each was evaluated at the tick's last iterate; at `poses` they are current.)
    const optimizer::SectionContactTerm::State& s = *p.state[i];
    beta[i] = s.valid ? s.ext.beta : INFINITY;
  }
  int nearest = 0;
  for (int i = 1; i < kSections; ++i) {
    if (beta[i] < beta[nearest]) nearest = i;
  }
  if (beta[nearest] > p.h) {
    Leave(k, u);
    return Next::kRelease;
  }
  // Where the point contact would be well conditioned again: at the middle section.
  const Eigen::Vector4d middle = MiddleU(k);
  const optimizer::SectionContactTerm& t = *p.term[0];
  contact::SurfacePairEval e;
  nurbs::SpanHint hint_f, hint_g;
  contact::EvaluatePair(t.f(), poses[static_cast<size_t>(t.body_a())], t.g(),
                        poses[static_cast<size_t>(t.body_b())], middle, &hint_f, &hint_g, &e);
  const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(e);
  if (rc.valid && rc.eigenvalues[1] > 0.0 &&
      rc.eigenvalues[0] > options_.leave * rc.eigenvalues[1] && nearest == 0) {
    Leave(k, u);
    return Next::kLeave;
  }
  // What the sections hold for the next solve: the gap where it dips between them (Margin).
  const double margin = Margin(&p, poses, beta, middle);
  for (int i = 0; i < kSections; ++i) p.state[i]->margin = margin;
  // A line whose λ_min has grown since the sections were spaced (LineSpacing) lets the gap dip
  // deeper between them: closer in about the middle once they are half as far again apart as
  // the dip allows (a hysteresis of 2.25 in the dip). Only while no dip is measured between
  // them: where there is one, the margin holds it, and sections respaced about the middle would
  // hold the margin measured between the old ones (measured: chain_soak respaced twice in the
  // second it came apart, at 1,336 s, and held the hour without respacing; with this condition
  // it does not respace on the soak at all).
  if (rc.valid && margin == 0.0) {
    const double need = LineSpacing(rc.eigenvalues[0], rc.eigenvalues[1], options_.dip);
    if (p.h > 1.5 * need) {
      p.h_free = std::min(p.h_free, need);
      if (Fit(&p, middle)) {
        Place(&p, middle);
        ++respaced_;
        return Next::kStay;
      }
    }
  }
  // Follow the line: toward the nearer side by half the spacing when it is nearer than the
  // middle (a line whose minimum has slid along). (Measured against a parabola through the
  // three moved to its lowest point: chain_soak --lines apart at 221 s instead of 566 s; and
  // against no moves: 205 s.) A move keeps the margin, measured where the gap dips.
  if (nearest != 0 && beta[nearest] < beta[0] - kMoveGap) {
    const Eigen::Vector4d to = middle + (kOffset[nearest] < 0.0 ? -0.5 : 0.5) * p.spacing * p.step;
    if (Fit(&p, to)) {  // (the spacing refitted to the room there)
      Place(&p, to);
      ++moves_;
    }
  }
  return Next::kStay;
}

double LineContacts::Margin(Pair* p, const std::vector<contact::BodyPose>& poses,
                            const double* beta, const Eigen::Vector4d& middle) const {
  // Three sections straddling a minimum of the gap along the line read it high by up to
  // ½ λ_min (h/2)² between them: on the paperclip soak's hooks, wires 1.9e-6 m through each other
  // while every section read 0 (docs/reliability.md, "Soak"). The section through the parabola's
  // lowest point measures how deep the gap goes there, and the three then hold the pair that
  // far apart. Measured, not extrapolated: on a straight line of minima (a rod in a groove) the
  // parabola through rounding differences, or through a section past the rod's end, has a
  // lowest point the gap does not reach, and the probe there reads what the sections do.
  double at = 0.0;
  if (!SectionDip(beta[1], beta[0], beta[2], &at)) return 0.0;
  // Placed as Place places a section, `at` spacings along the line; followed from the nearer
  // section's extremum (not a blend: g's parameters and the line's may straddle a periodic seam,
  // as on a wire's tube).
  const Eigen::Vector4d in =
      contact::IntoPairDomain(p->term[0]->f(), p->term[0]->g(), middle + at * p->spacing * p->step);
  const optimizer::SectionContactTerm::State& nearer =
      *p->state[std::abs(at) < 0.5 ? 0 : (at < 0.0 ? 1 : 2)];
  p->probe->Place(p->fixed, in[p->fixed], nearer.u);
  p->term[0]->Update(poses, p->probe);
  const contact::CurveSurfaceExtremum& e = p->probe->ext;
  if (e.status != contact::ExtremalStatus::kConverged || !std::isfinite(e.beta)) return 0.0;
  return std::max(0.0, std::min({beta[0], beta[1], beta[2]}) - e.beta);
}

}  // namespace tangent::server
