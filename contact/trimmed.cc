#include "contact/trimmed.h"

#include <cmath>

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

int TrimEdges::PieceOf(const nurbs::TrimmedDomain::Closest& near) const {
  const std::vector<Piece>& loop = pieces_[static_cast<size_t>(near.loop)];
  for (size_t p = 0; p < loop.size(); ++p) {
    const nurbs::KnotVector& k = loop[p].c.knots();
    if (loop[p].curve == near.curve && near.t >= k.domain_begin() && near.t <= k.domain_end()) {
      return static_cast<int>(p);
    }
  }
  return 0;
}

void TrimEdges::Start(const nurbs::TrimmedDomain::Closest& near, const Eigen::Vector2d& st,
                      Edge* e) const {
  const std::vector<Piece>& loop = pieces_[static_cast<size_t>(near.loop)];
  const int piece = PieceOf(near);
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

namespace {

// One side of an edge–edge walk: where the extremum stopped at the end of its piece (not a
// periodic one), moves to the neighbour there and puts the parameter at its near end; false
// when the neighbour is the piece it came from (the extremum is the joint between them).
bool WalkOn(const TrimEdges& edges, int loop, int* piece, int* from, double* x) {
  const std::vector<TrimEdges::Piece>& pieces = edges.loops()[static_cast<size_t>(loop)];
  const int n = static_cast<int>(pieces.size());
  const nurbs::KnotVector& k = pieces[static_cast<size_t>(*piece)].c.knots();
  const bool at_end = *x >= 0.5 * (k.domain_begin() + k.domain_end());
  const int next = (*piece + (at_end ? 1 : n - 1)) % n;
  if (next == *from) return false;
  *from = *piece;
  *piece = next;
  const nurbs::KnotVector& kn = pieces[static_cast<size_t>(next)].c.knots();
  *x = at_end ? kn.domain_begin() : kn.domain_end();
  return true;
}

}  // namespace

void SolveEdgeEdge(const TrimEdges& edges_f, const BodyPose& pose_f, const TrimEdges& edges_g,
                   const BodyPose& pose_g, const Eigen::Vector3d& side, EdgeEdgeFollow* e) {
  const int n = static_cast<int>(edges_f.loops()[static_cast<size_t>(e->loop_f)].size() +
                                 edges_g.loops()[static_cast<size_t>(e->loop_g)].size());
  int from_f = -1, from_g = -1;
  bool joint_f = false, joint_g = false;
  CurveCurveEval& ev = e->eval;
  for (int walk = 0; walk <= n; ++walk) {
    e->ext = SolveCurveCurve(edges_f.Curve(e->loop_f, e->piece_f), pose_f,
                             edges_g.Curve(e->loop_g, e->piece_g), pose_g, e->x, {}, &ev);
    e->x = e->ext.x;
    bool moved = false;
    if (e->ext.at_bound[0] && !joint_f) {
      moved = WalkOn(edges_f, e->loop_f, &e->piece_f, &from_f, &e->x[0]);
      joint_f = !moved;
    }
    if (!moved && e->ext.at_bound[1] && !joint_g) {
      moved = WalkOn(edges_g, e->loop_g, &e->piece_g, &from_g, &e->x[1]);
      joint_g = !moved;
    }
    if (!moved) break;
  }
  // Held only at joints that both neighbours push into: the loops' extremum (as TrimEdges::Solve).
  if (e->ext.status == ExtremalStatus::kAtBoundary && (!e->ext.at_bound[0] || joint_f) &&
      (!e->ext.at_bound[1] || joint_g)) {
    e->ext.status = ExtremalStatus::kConverged;
  }
  // ν: the common normal where both parameters are free, else along d; on `side`'s side.
  Eigen::Vector3d nu;
  e->common_normal = !e->ext.at_bound[0] && !e->ext.at_bound[1] && CommonNormal(ev, 1.0, &nu);
  if (!e->common_normal) {
    const double len = ev.d.norm();
    nu = len > 0.0 ? Eigen::Vector3d(ev.d / len) : side.normalized();
  }
  e->nu = nu.dot(side) < 0.0 ? Eigen::Vector3d(-nu) : nu;
}

namespace {

// Whether uv lies on the material of `edges`' face, through the memo as MeasureTrimmed uses it;
// when not, *near is the loops' point nearest uv.
bool MaterialAt(const TrimEdges& edges, const Eigen::Vector2d& uv, MaterialMemo* memo,
                nurbs::TrimmedDomain::Closest* near) {
  near->loop = -1;
  if (memo && memo->clearance > 0.0 && (uv - memo->uv).norm() < memo->clearance) return true;
  double clearance = 0.0;
  const bool material = edges.trim().Contains(uv, near, &clearance);
  if (memo) *memo = {uv, material ? clearance : 0.0};
  if (!material && near->loop < 0) *near = edges.trim().Nearest(uv);
  return material;
}

// The face's parameters at τ on one of its edge pieces (the piece's domain point).
Eigen::Vector2d PieceUv(const TrimEdges& edges, int loop, int piece, double tau) {
  return edges.loops()[static_cast<size_t>(loop)][static_cast<size_t>(piece)].c.Evaluate(tau, 0).C;
}

// The in-surface direction into the material at τ on an edge piece, world: m = n × E'/|E'|,
// n = S_u × S_v (the loops keep the material on their left in the domain), E' the edge's world
// tangent there.
Eigen::Vector3d IntoMaterial(const TrimEdges& edges, int loop, int piece, double tau,
                             const BodyPose& pose, const Eigen::Vector3d& tangent) {
  const Eigen::Vector2d uv = PieceUv(edges, loop, piece, tau);
  const nurbs::SurfacePoint sp = edges.surface().Evaluate(uv[0], uv[1], 1);
  const Eigen::Vector3d n = pose.R_WB * sp.S_u.cross(sp.S_v);
  return n.cross(tangent).normalized();
}

// An edge of `edges`' face against the other face, seeded at τ on (loop, piece) with the other
// face's parameters `other` (an edge–edge contact giving one edge up).
TrimEdges::Edge EdgeAt(const TrimEdges& edges, int loop, int piece, double tau,
                       const Eigen::Vector2d& other) {
  TrimEdges::Edge e;
  e.loop = loop;
  e.piece = piece;
  e.curve = edges.loops()[static_cast<size_t>(loop)][static_cast<size_t>(piece)].curve;
  e.u << other, tau;
  return e;
}

// The measure of an edge of f against g's face (`of_g`: an edge of g against f's face, its
// points swapped back into (f, g) order and β's direction with them).
TrimmedMeasure EdgeMeasure(const TrimEdges::Edge& e, bool of_g) {
  TrimmedMeasure m;
  m.on_edge = true;
  m.form = of_g ? TrimmedForm::kEdgeOfG : TrimmedForm::kEdgeOfF;
  m.edge = e;
  m.beta = e.ext.beta;
  m.p_f = of_g ? e.ext.p_f : e.ext.p_g;  // the solver's curve is the edge, its surface the face
  m.p_g = of_g ? e.ext.p_g : e.ext.p_f;
  m.status = e.ext.status;
  return m;
}

// The measure of two edges' contact.
TrimmedMeasure EdgeEdgeMeasure(const EdgeEdgeFollow& ee) {
  TrimmedMeasure m;
  m.on_edge = true;
  m.form = TrimmedForm::kEdgeEdge;
  m.edge_edge = ee;
  m.p_f = ee.ext.p_a;
  m.p_g = ee.ext.p_b;
  m.beta = (m.p_f - m.p_g).dot(ee.nu);
  m.status = ee.ext.status;
  return m;
}

}  // namespace

TrimmedMeasure MeasureTrimmedPair(const TrimEdges& edges_f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const TrimEdges* edges_g,
                                  const BodyPose& pose_g, const SurfaceSurfaceExtremum* face,
                                  const TrimmedMeasure* from, MaterialMemo* memo_f,
                                  MaterialMemo* memo_g) {
  const TrimmedForm was = from ? from->form : TrimmedForm::kFace;
  if (!edges_g) {
    TrimmedMeasure m = MeasureTrimmed(edges_f, pose_f, g, pose_g, *face,
                                      was == TrimmedForm::kEdgeOfF ? &from->edge : nullptr, memo_f);
    m.form = m.on_edge ? TrimmedForm::kEdgeOfF : TrimmedForm::kFace;
    return m;
  }
  const nurbs::NurbsSurface& f = edges_f.surface();
  // The faces' extremum where its points lie on both materials. (Without it, an edge contact
  // followed says by its multiplier when the faces should be solved: face_wanted.)
  nurbs::TrimmedDomain::Closest near_f, near_g;
  const bool on_f = face && MaterialAt(edges_f, face->u.head<2>(), memo_f, &near_f);
  const bool on_g = face && MaterialAt(*edges_g, face->u.tail<2>(), memo_g, &near_g);
  // An edge contact is left for the face only at an extremum (a face term held where it jumped,
  // or reseeded at an edge contact's points, is not one).
  const bool extremum = face && (face->status == ExtremalStatus::kConverged ||
                                 face->status == ExtremalStatus::kSingular);
  if (face && on_f && on_g && (extremum || was == TrimmedForm::kFace)) {
    TrimmedMeasure m;
    m.beta = face->beta;
    m.p_f = face->p_f;
    m.p_g = face->p_g;
    m.status = face->status;
    return m;
  }
  // Else an edge contact, followed in its own form while it holds (seed 001's constraints as a
  // local problem: min |a − b| over both materials). An edge against a face holds while its
  // point on the face lies on that face's material; two edges hold while neither face offers a
  // nearer point, i.e. while each edge constraint's multiplier is non-negative: moving b into
  // g's material by ε changes β by −ε ν·m_g, moving a into f's by +ε ν·m_f.
  EdgeEdgeFollow ee;
  Eigen::Vector3d side;  // from g's edge towards f's where they are apart
  nurbs::TrimmedDomain::Closest near;
  if (was == TrimmedForm::kEdgeEdge) {
    ee = from->edge_edge;
    SolveEdgeEdge(edges_f, pose_f, *edges_g, pose_g, ee.nu, &ee);
    const double hold_g = -ee.nu.dot(
        IntoMaterial(*edges_g, ee.loop_g, ee.piece_g, ee.x[1], pose_g, ee.eval.b.world.C1));
    const double hold_f = ee.nu.dot(
        IntoMaterial(edges_f, ee.loop_f, ee.piece_f, ee.x[0], pose_f, ee.eval.a.world.C1));
    if (hold_g < 0.0 && hold_g <= hold_f) {  // g's material offers a nearer point: f's edge on g
      TrimEdges::Edge e = EdgeAt(edges_f, ee.loop_f, ee.piece_f, ee.x[0],
                                 PieceUv(*edges_g, ee.loop_g, ee.piece_g, ee.x[1]));
      edges_f.Solve(g, pose_g, pose_f, &e);
      if (MaterialAt(*edges_g, e.ext.u.head<2>(), nullptr, &near)) return EdgeMeasure(e, false);
    } else if (hold_f < 0.0) {  // f's material does: g's edge on f
      TrimEdges::Edge e = EdgeAt(*edges_g, ee.loop_g, ee.piece_g, ee.x[1],
                                 PieceUv(edges_f, ee.loop_f, ee.piece_f, ee.x[0]));
      edges_g->Solve(f, pose_f, pose_g, &e);
      if (MaterialAt(edges_f, e.ext.u.head<2>(), nullptr, &near)) return EdgeMeasure(e, true);
    }
  } else {
    // An edge against a face: followed (or started at the loop point nearest the face's point
    // off its material), kept while its point on the face lies on that face's material.
    const bool of_g = was == TrimmedForm::kEdgeOfG || (was == TrimmedForm::kFace && on_f);
    const TrimEdges& mine = of_g ? *edges_g : edges_f;
    const TrimEdges& theirs = of_g ? edges_f : *edges_g;
    const BodyPose& pose_mine = of_g ? pose_g : pose_f;
    const BodyPose& pose_theirs = of_g ? pose_f : pose_g;
    TrimEdges::Edge e;
    if (was != TrimmedForm::kFace) {
      e = from->edge;
    } else {
      const Eigen::Vector2d theirs_uv = of_g ? face->u.head<2>() : face->u.tail<2>();
      mine.StartNear(of_g ? near_g : near_f, theirs.surface(), pose_theirs, pose_mine, theirs_uv,
                     &e);
    }
    mine.Solve(theirs.surface(), pose_theirs, pose_mine, &e);
    if (MaterialAt(theirs, e.ext.u.head<2>(), nullptr, &near)) {
      TrimmedMeasure m = EdgeMeasure(e, of_g);
      // Its own edge constraint's multiplier: moving the edge's point into its material by ε
      // changes β = (E − G)·n by ε n·m (n the other face's normal there). Negative: the face
      // offers a nearer point, and the faces' extremum should be solved from here.
      if (!face && !e.ext.at_bound[0] && !e.ext.at_bound[1] && !e.ext.at_bound[2]) {
        int span = 0;
        nurbs::SpanHint hint;
        const Eigen::Vector3d tangent =
            pose_mine.R_WB * mine.Curve(e).Evaluate(e.u[2], &span, &hint).C1;
        const Eigen::Vector3d into =
            IntoMaterial(mine, e.loop, e.piece, e.u[2], pose_mine, tangent);
        m.face_wanted = e.ext.R_WCf.col(2).dot(into) < 0.0;
      }
      return m;
    }
    // Its point left the other face's material: the two edges, from the edge's point and the
    // other loop's point nearest the point it left for. β's side: the face's normal.
    const int piece = theirs.PieceOf(near);
    if (of_g) {
      ee.loop_f = near.loop;
      ee.piece_f = piece;
      ee.loop_g = e.loop;
      ee.piece_g = e.piece;
      ee.x << near.t, e.u[2];
      side = -e.ext.R_WCf.col(2);  // against f's normal
    } else {
      ee.loop_f = e.loop;
      ee.piece_f = e.piece;
      ee.loop_g = near.loop;
      ee.piece_g = piece;
      ee.x << e.u[2], near.t;
      side = e.ext.R_WCf.col(2);  // along g's normal
    }
    SolveEdgeEdge(edges_f, pose_f, *edges_g, pose_g, side, &ee);
  }
  return EdgeEdgeMeasure(ee);
}

Eigen::Vector4d PointParameters(const TrimEdges& edges_f, const TrimEdges& edges_g,
                                const TrimmedMeasure& m, const Eigen::Vector4d& face_u) {
  Eigen::Vector4d u = face_u;
  switch (m.form) {
    case TrimmedForm::kEdgeOfF:  // the solver's surface is g: its (s, t), then τ on f's edge
      u << PieceUv(edges_f, m.edge.loop, m.edge.piece, m.edge.u[2]), m.edge.ext.u.head<2>();
      break;
    case TrimmedForm::kEdgeOfG:
      u << m.edge.ext.u.head<2>(), PieceUv(edges_g, m.edge.loop, m.edge.piece, m.edge.u[2]);
      break;
    case TrimmedForm::kEdgeEdge: {
      const EdgeEdgeFollow& ee = m.edge_edge;
      u << PieceUv(edges_f, ee.loop_f, ee.piece_f, ee.x[0]),
          PieceUv(edges_g, ee.loop_g, ee.piece_g, ee.x[1]);
      break;
    }
    case TrimmedForm::kFace:
      break;
  }
  return u;
}

bool MeasureTrimmedPairAt(const TrimEdges& edges_f, const BodyPose& pose_f,
                          const TrimEdges& edges_g, const BodyPose& pose_g,
                          const Eigen::Vector4d& u, TrimmedMeasure* m) {
  constexpr double kOnLoop = 1e-9;  // parameter units: an edge point is its loop's point exactly
  const nurbs::TrimmedDomain::Closest near_f = edges_f.trim().Nearest(u.head<2>());
  const nurbs::TrimmedDomain::Closest near_g = edges_g.trim().Nearest(u.tail<2>());
  const bool on_f = near_f.loop >= 0 && std::abs(near_f.signed_distance) <= kOnLoop;
  const bool on_g = near_g.loop >= 0 && std::abs(near_g.signed_distance) <= kOnLoop;
  if (!on_f && !on_g) return false;
  if (on_f && on_g) {
    // β's side: along g's normal and against f's (the edge forms' conventions).
    auto normal = [](const TrimEdges& e, const Eigen::Vector2d& uv, const BodyPose& pose) {
      const nurbs::SurfacePoint p = e.surface().Evaluate(uv[0], uv[1], 1);
      return Eigen::Vector3d(pose.R_WB * p.S_u.cross(p.S_v).normalized());
    };
    const Eigen::Vector3d side =
        normal(edges_g, u.tail<2>(), pose_g) - normal(edges_f, u.head<2>(), pose_f);
    EdgeEdgeFollow ee;
    ee.loop_f = near_f.loop;
    ee.piece_f = edges_f.PieceOf(near_f);
    ee.loop_g = near_g.loop;
    ee.piece_g = edges_g.PieceOf(near_g);
    ee.x << near_f.t, near_g.t;
    SolveEdgeEdge(edges_f, pose_f, edges_g, pose_g, side, &ee);
    *m = EdgeEdgeMeasure(ee);
    return true;
  }
  if (on_f) {
    TrimEdges::Edge e =
        EdgeAt(edges_f, near_f.loop, edges_f.PieceOf(near_f), near_f.t, u.tail<2>());
    edges_f.Solve(edges_g.surface(), pose_g, pose_f, &e);
    *m = EdgeMeasure(e, false);
  } else {
    TrimEdges::Edge e =
        EdgeAt(edges_g, near_g.loop, edges_g.PieceOf(near_g), near_g.t, u.head<2>());
    edges_g.Solve(edges_f.surface(), pose_f, pose_g, &e);
    *m = EdgeMeasure(e, true);
  }
  return true;
}

}  // namespace tangent::contact
