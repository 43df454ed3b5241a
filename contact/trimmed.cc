#include "contact/trimmed.h"

#include "nurbs/refinement.h"

namespace tangent::contact {

namespace {

// Whether two pieces meet with one first derivative (C¹: position to 1e-12 of the curve's size,
// derivative to 1e-9 relative), as the standard rational circle's quarter points and its closure
// do: the edge's Newton then crosses the joint instead of stopping at it.
bool JoinsSmoothly(const nurbs::NurbsCurve2d& left, const nurbs::NurbsCurve2d& right) {
  const nurbs::CurvePoint<2> a = left.Evaluate(left.knots().domain_end(), 1);
  const nurbs::CurvePoint<2> b = right.Evaluate(right.knots().domain_begin(), 1);
  const double size = 1.0 + a.C.norm();
  return (a.C - b.C).norm() <= 1e-12 * size &&
         (a.C1 - b.C1).norm() <= 1e-9 * (a.C1.norm() + b.C1.norm()) + 1e-14 * size;
}

}  // namespace

TrimEdges::TrimEdges(const nurbs::NurbsSurface* f, const nurbs::TrimmedDomain* trim)
    : f_(f), trim_(trim) {
  for (const nurbs::TrimLoop& loop : trim_->loops()) {
    pieces_.emplace_back();
    for (size_t ci = 0; ci < loop.curves.size(); ++ci) {
      const nurbs::NurbsCurve2d& c = loop.curves[ci];
      nurbs::NurbsCurve2d rest = c;
      for (double knot : c.knots().Breakpoints()) {
        const nurbs::KnotVector& k = rest.knots();
        if (c.knots().Multiplicity(knot) < c.degree()) continue;  // C¹ or smoother there
        if (!(knot > k.domain_begin() && knot < k.domain_end())) continue;
        auto [left, right] = nurbs::Split(rest, knot);
        if (JoinsSmoothly(left, right)) continue;  // C¹ although the knot is full
        pieces_.back().push_back({static_cast<int>(ci), std::move(left)});
        rest = std::move(right);
      }
      pieces_.back().push_back({static_cast<int>(ci), std::move(rest)});
    }
    // One smooth piece closing on itself with one derivative: its parameter wraps round.
    Piece& first = pieces_.back().front();
    first.periodic = pieces_.back().size() == 1 && JoinsSmoothly(first.c, first.c);
  }
}

void TrimEdges::Start(const nurbs::TrimmedDomain::Closest& near, const Eigen::Vector2d& st,
                      Edge* e) const {
  const std::vector<Piece>& loop = pieces_[static_cast<size_t>(near.loop)];
  int piece = 0;
  for (size_t p = 0; p < loop.size(); ++p) {
    const nurbs::KnotVector& k = loop[p].c.knots();
    if (loop[p].curve == near.curve && near.t >= k.domain_begin() && near.t <= k.domain_end()) {
      piece = static_cast<int>(p);
      break;
    }
  }
  e->loop = near.loop;
  e->piece = piece;
  e->curve = loop[static_cast<size_t>(piece)].curve;
  e->u << st, near.t;
}

void TrimEdges::StartNear(const nurbs::TrimmedDomain::Closest& near, const nurbs::NurbsSurface& g,
                          const BodyPose& pose_g, const BodyPose& pose_f, const Eigen::Vector2d& st,
                          Edge* e) const {
  Start(near, st, e);
  int span = 0;
  nurbs::SpanHint hint;
  const Eigen::Vector3d E = pose_f.Point(Curve(*e).Evaluate(near.t, &span, &hint).C);
  const PointSurfaceExtremum p = SolvePointSurface(E, g, pose_g, st);
  if (p.u.allFinite()) e->u.head<2>() = p.u;
}

void TrimEdges::Solve(const nurbs::NurbsSurface& g, const BodyPose& pose_g, const BodyPose& pose_f,
                      Edge* e) const {
  const std::vector<Piece>& loop = pieces_[static_cast<size_t>(e->loop)];
  const int n = static_cast<int>(loop.size());
  int from = -1;
  bool at_joint = false;
  for (int walk = 0; walk <= n; ++walk) {
    const Piece& x = loop[static_cast<size_t>(e->piece)];
    e->ext = SolveCurveSurface(g, pose_g, BodyCurve(f_, &x.c, x.periodic), pose_f, e->u);
    e->u = e->ext.u;
    if (!e->ext.at_bound[2]) break;
    const bool at_end = e->u[2] >= 0.5 * (x.c.knots().domain_begin() + x.c.knots().domain_end());
    const int next = (e->piece + (at_end ? 1 : n - 1)) % n;
    if (next == from) {  // back where it came from: the extremum is the joint between the two
      at_joint = true;
      break;
    }
    from = e->piece;
    e->piece = next;
    const nurbs::KnotVector& k = loop[static_cast<size_t>(next)].c.knots();
    e->u[2] = at_end ? k.domain_begin() : k.domain_end();
  }
  e->curve = loop[static_cast<size_t>(e->piece)].curve;
  // Held at a joint that both neighbours push into: the loop's extremum is that point (a corner,
  // or a smooth joint such as a rational circle's quarter point), not a border of the loop,
  // which has none. It stays flagged at_bound[2] (measured along the line between the points).
  if (at_joint && e->ext.status == ExtremalStatus::kAtBoundary && !e->ext.at_bound[0] &&
      !e->ext.at_bound[1]) {
    e->ext.status = ExtremalStatus::kConverged;
  }
}

TrimmedMeasure MeasureTrimmed(const TrimEdges& edges, const BodyPose& pose_f,
                              const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                              const SurfaceSurfaceExtremum& face, const TrimEdges::Edge* from,
                              MaterialMemo* memo) {
  TrimmedMeasure m;
  const Eigen::Vector2d uv = face.u.head<2>();
  nurbs::TrimmedDomain::Closest near;
  // On the material when within the remembered clearance of a point that was (exactly the
  // classification's own answer there: no chord's band and no border is nearer).
  bool material = memo && memo->clearance > 0.0 && (uv - memo->uv).norm() < memo->clearance;
  int excluded_by = -1;
  if (!material) {
    double clearance = 0.0;
    material = edges.trim().Contains(uv, &near, &clearance, &excluded_by);
    if (memo) *memo = {uv, material ? clearance : 0.0};
  }
  if (material) {
    m.beta = face.beta;
    m.p_f = face.p_f;
    m.p_g = face.p_g;
    m.status = face.status;
    return m;
  }
  m.on_edge = true;
  // The edge followed stays on its loop while that is the nearest: with one loop, always; a
  // loop whose polygon excludes the point beyond every band is the nearest (any path to another
  // loop crosses it: a CAD face's outer loop need not be searched while its hole's rim is
  // followed); else the nearest loop point decides.
  const bool one_loop = edges.trim().loops().size() == 1;
  bool keep = from && (one_loop || (near.loop < 0 && excluded_by == from->loop));
  if (!keep) {
    if (near.loop < 0) near = edges.trim().Nearest(uv);
    keep = from && from->loop == near.loop;
  }
  if (keep) {
    m.edge = *from;
  } else {
    edges.StartNear(near, g, pose_g, pose_f, face.u.tail<2>(), &m.edge);
  }
  edges.Solve(g, pose_g, pose_f, &m.edge);
  const CurveSurfaceExtremum& e = m.edge.ext;
  m.beta = e.beta;
  m.p_f = e.p_g;  // the solver's curve is f's edge, its surface g
  m.p_g = e.p_f;
  m.status = e.status;
  return m;
}

}  // namespace tangent::contact
