// Trimming loops (trim.h, docs/trimming.md). CGAL's exact predicates decide the polygon's
// crossings and point locations; the curves decide everything inside the certified band.

#include "nurbs/trim.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "nurbs/refinement.h"

namespace tangent::nurbs {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = Kernel::Point_2;
using S2 = Kernel::Segment_2;

std::string Pt(const Eigen::Vector2d& p) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.9g, %.9g)", p[0], p[1]);
  return text;
}

std::string Num(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

P2 ToP2(const Eigen::Vector2d& p) { return {p[0], p[1]}; }

Eigen::Vector2d Start(const NurbsCurve2d& c) { return c.Evaluate(c.knots().domain_begin(), 0).C; }
Eigen::Vector2d End(const NurbsCurve2d& c) { return c.Evaluate(c.knots().domain_end(), 0).C; }

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b, double* s = nullptr) {
  const Eigen::Vector2d d = b - a;
  const double l2 = d.squaredNorm();
  const double f = l2 > 0.0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  if (s) *s = f;
  return (a + f * d - p).norm();
}

double SegmentDistance(const TrimmedDomain::Chord& x, const TrimmedDomain::Chord& y) {
  if (CGAL::do_intersect(S2(ToP2(x.a), ToP2(x.b)), S2(ToP2(y.a), ToP2(y.b)))) return 0.0;
  return std::min({PointSegmentDistance(x.a, y.a, y.b), PointSegmentDistance(x.b, y.a, y.b),
                   PointSegmentDistance(y.a, x.a, x.b), PointSegmentDistance(y.b, x.a, x.b)});
}

// The curve run backwards: t → (t_first + t_last) − t over its knot vector.
NurbsCurve2d Reversed(const NurbsCurve2d& c) {
  const std::vector<double>& k = c.knots().knots();
  std::vector<double> knots(k.size());
  for (size_t i = 0; i < k.size(); ++i) knots[i] = k.front() + k.back() - k[k.size() - 1 - i];
  std::vector<NurbsCurve2d::HPoint> cpw(c.weighted_points().rbegin(), c.weighted_points().rend());
  return NurbsCurve2d::FromHomogeneous(KnotVector(c.degree(), knots), cpw);
}

void Reverse(TrimLoop* loop) {
  std::reverse(loop->curves.begin(), loop->curves.end());
  for (NurbsCurve2d& c : loop->curves) c = Reversed(c);
}

// A Bézier piece of a loop's curve, with the band of its control polygon about its chord.
struct Piece {
  NurbsCurve2d bezier;
  int curve = 0;
  double t0 = 0.0, t1 = 0.0;
  double band = 0.0;
};

double BandOf(const NurbsCurve2d& bezier) {
  const Eigen::Vector2d a = bezier.point(0), b = bezier.point(bezier.num_points() - 1);
  double band = 0.0;
  for (int i = 1; i + 1 < bezier.num_points(); ++i) {
    band = std::max(band, PointSegmentDistance(bezier.point(i), a, b));
  }
  return band;
}

Piece MakePiece(NurbsCurve2d bezier, int curve) {
  Piece p{std::move(bezier), curve, 0.0, 0.0, 0.0};
  p.t0 = p.bezier.knots().domain_begin();
  p.t1 = p.bezier.knots().domain_end();
  p.band = BandOf(p.bezier);
  return p;
}

std::pair<Piece, Piece> Halve(const Piece& p) {
  auto [left, right] = Split(p.bezier, 0.5 * (p.t0 + p.t1));
  return {MakePiece(std::move(left), p.curve), MakePiece(std::move(right), p.curve)};
}

double SignedArea(const std::vector<Piece>& pieces) {
  double area = 0.0;
  for (const Piece& p : pieces) {
    const Eigen::Vector2d a = p.bezier.point(0), b = p.bezier.point(p.bezier.num_points() - 1);
    area += a[0] * b[1] - b[0] * a[1];
  }
  return 0.5 * area;
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a[0] * b[1] - a[1] * b[0];
}

}  // namespace

std::string TrimmedDomain::LoopName(int loop) const {
  if (has_outer_ && loop == 0) return "outer loop";
  return "hole " + std::to_string(loop - (has_outer_ ? 1 : 0));
}

TrimmedDomain::TrimmedDomain(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                             std::optional<TrimLoop> outer, std::vector<TrimLoop> holes,
                             const TrimOptions& options, std::vector<std::string>* warnings)
    : lo_(lo), hi_(hi), has_outer_(outer.has_value()) {
  if (!(lo.allFinite() && hi.allFinite() && lo[0] < hi[0] && lo[1] < hi[1])) {
    throw TrimError("trim: the surface's domain " + Pt(lo) + " to " + Pt(hi) + " is empty");
  }
  if (outer) loops_.push_back(std::move(*outer));
  for (TrimLoop& h : holes) loops_.push_back(std::move(h));
  const double diagonal = (hi - lo).norm();
  const double gap_allowed = options.closure_tolerance * diagonal;
  const double band = options.band * diagonal;
  const int num_loops = static_cast<int>(loops_.size());

  // 1. Closed: each curve starts where the previous one ends.
  for (int l = 0; l < num_loops; ++l) {
    const std::vector<NurbsCurve2d>& curves = loops_[static_cast<size_t>(l)].curves;
    if (curves.empty()) throw TrimError("trim: " + LoopName(l) + " has no curves");
    for (size_t c = 0; c < curves.size(); ++c) {
      const size_t next = (c + 1) % curves.size();
      const Eigen::Vector2d end = End(curves[c]), start = Start(curves[next]);
      const double gap = (end - start).norm();
      if (!(gap <= gap_allowed)) {
        throw TrimError("trim: " + LoopName(l) + " is not closed: curve " + std::to_string(c) +
                        " ends at " + Pt(end) + " but curve " + std::to_string(next) +
                        " starts at " + Pt(start) + ": a gap of " + Num(gap) + " (tolerance " +
                        Num(gap_allowed) + ")");
      }
    }
  }

  // 2. The certified polygonization: Bézier pieces halved until their control polygons lie
  //    within the band of their chords.
  std::vector<std::vector<Piece>> pieces(static_cast<size_t>(num_loops));
  auto polygonize = [&](int l) {
    std::vector<Piece>& out = pieces[static_cast<size_t>(l)];
    out.clear();
    const std::vector<NurbsCurve2d>& curves = loops_[static_cast<size_t>(l)].curves;
    for (size_t c = 0; c < curves.size(); ++c) {
      for (NurbsCurve2d& b : ExtractBezier(curves[c])) {
        std::vector<Piece> stack{MakePiece(std::move(b), static_cast<int>(c))};
        while (!stack.empty()) {
          Piece p = std::move(stack.back());
          stack.pop_back();
          if (p.band <= band || p.t1 - p.t0 <= 1e-12 * (1.0 + std::abs(p.t0))) {
            out.push_back(std::move(p));
          } else {
            auto [left, right] = Halve(p);
            stack.push_back(std::move(right));  // (left is processed first: in order)
            stack.push_back(std::move(left));
          }
        }
      }
    }
  };
  for (int l = 0; l < num_loops; ++l) polygonize(l);

  // 3. Inside the domain: every chord's end (a point of the curve) within [lo, hi].
  for (int l = 0; l < num_loops; ++l) {
    for (const Piece& p : pieces[static_cast<size_t>(l)]) {
      for (const Eigen::Vector2d& x :
           {p.bezier.point(0), p.bezier.point(p.bezier.num_points() - 1)}) {
        if ((x.array() < lo.array() - gap_allowed).any() ||
            (x.array() > hi.array() + gap_allowed).any()) {
          throw TrimError("trim: " + LoopName(l) + ": curve " + std::to_string(p.curve) +
                          " leaves the surface's domain " + Pt(lo) + " to " + Pt(hi) + " at " +
                          Pt(x));
        }
      }
    }
  }

  // 4. No crossings, and bands apart: chords that are not neighbours in one loop must be farther
  //    apart than their two bands (else both pieces are halved and checked again); chords that
  //    cross are an error. Neighbours must not fold back onto each other.
  auto rebuild_chords = [&] {
    chords_.clear();
    loop_chords_.assign(static_cast<size_t>(num_loops), {});
    for (int l = 0; l < num_loops; ++l) {
      for (const Piece& p : pieces[static_cast<size_t>(l)]) {
        loop_chords_[static_cast<size_t>(l)].push_back(static_cast<int>(chords_.size()));
        chords_.push_back({p.bezier.point(0), p.bezier.point(p.bezier.num_points() - 1), l, p.curve,
                           p.t0, p.t1, p.band});
      }
    }
    loop_box_.assign(static_cast<size_t>(num_loops), {});
    for (int l = 0; l < num_loops; ++l) {
      LoopBox& box = loop_box_[static_cast<size_t>(l)];
      box.lo = box.hi = chords_[static_cast<size_t>(loop_chords_[static_cast<size_t>(l)][0])].a;
      for (int c : loop_chords_[static_cast<size_t>(l)]) {
        const Chord& x = chords_[static_cast<size_t>(c)];
        box.lo = box.lo.cwiseMin(x.a).cwiseMin(x.b);
        box.hi = box.hi.cwiseMax(x.a).cwiseMax(x.b);
        box.band = std::max(box.band, x.band);
      }
      const Eigen::Vector2d size = box.hi - box.lo;
      double length = 0.0;
      bool on_sides = size.minCoeff() > 0.0;
      for (int c : loop_chords_[static_cast<size_t>(l)]) {
        const Chord& x = chords_[static_cast<size_t>(c)];
        on_sides =
            on_sides && ((x.a[0] == x.b[0] && (x.a[0] == box.lo[0] || x.a[0] == box.hi[0])) ||
                         (x.a[1] == x.b[1] && (x.a[1] == box.lo[1] || x.a[1] == box.hi[1])));
        length += (x.b - x.a).norm();
      }
      const double perimeter = 2.0 * size.sum();
      box.rectangle = on_sides && std::abs(length - perimeter) <= 1e-12 * perimeter;
    }
  };
  auto neighbours = [&](int i, int j) {
    const Chord &x = chords_[static_cast<size_t>(i)], &y = chords_[static_cast<size_t>(j)];
    if (x.loop != y.loop) return false;
    const int n = static_cast<int>(loop_chords_[static_cast<size_t>(x.loop)].size());
    const int first = loop_chords_[static_cast<size_t>(x.loop)].front();
    const int a = i - first, b = j - first;
    return (a + 1) % n == b || (b + 1) % n == a;
  };
  constexpr int kRounds = 24;
  auto certify = [&] {
    for (int round = 0;; ++round) {
      rebuild_chords();
      const int n = static_cast<int>(chords_.size());
      std::vector<bool> halve(static_cast<size_t>(n), false);
      bool any = false;
      for (int i = 0; i < n; ++i) {
        const Chord& x = chords_[static_cast<size_t>(i)];
        for (int j = i + 1; j < n; ++j) {
          const Chord& y = chords_[static_cast<size_t>(j)];
          const double reach = x.band + y.band + gap_allowed;
          if (std::max(x.a[0], x.b[0]) + reach < std::min(y.a[0], y.b[0]) ||
              std::max(y.a[0], y.b[0]) + reach < std::min(x.a[0], x.b[0]) ||
              std::max(x.a[1], x.b[1]) + reach < std::min(y.a[1], y.b[1]) ||
              std::max(y.a[1], y.b[1]) + reach < std::min(x.a[1], x.b[1])) {
            continue;
          }
          if (neighbours(i, j)) {
            const Eigen::Vector2d dx = x.b - x.a, dy = y.b - y.a;
            if (std::abs(Cross(dx, dy)) <= 1e-12 * dx.norm() * dy.norm() && dx.dot(dy) < 0.0) {
              throw TrimError("trim: " + LoopName(x.loop) + " turns back on itself at " +
                              Pt(x.a == y.b ? x.a : x.b));
            }
            continue;
          }
          const double d = SegmentDistance(x, y);
          if (d == 0.0) {
            const std::string what =
                x.loop == y.loop ? LoopName(x.loop) + " crosses or touches itself"
                                 : LoopName(y.loop) + " crosses or touches the " + LoopName(x.loop);
            throw TrimError("trim: " + what + ": curve " + std::to_string(x.curve) + " near " +
                            Pt(0.5 * (x.a + x.b)) + " and curve " + std::to_string(y.curve) +
                            " near " + Pt(0.5 * (y.a + y.b)));
          }
          if (d <= x.band + y.band) {
            halve[static_cast<size_t>(i)] = halve[static_cast<size_t>(j)] = true;
            any = true;
          }
        }
      }
      if (!any) break;
      if (round == kRounds) {
        for (int i = 0; i < n; ++i) {
          if (!halve[static_cast<size_t>(i)]) continue;
          const Chord& x = chords_[static_cast<size_t>(i)];
          throw TrimError("trim: " + LoopName(x.loop) + " touches itself or another loop near " +
                          Pt(0.5 * (x.a + x.b)) + " (closer than " + Num(x.band) + ")");
        }
      }
      for (int l = 0, k = 0; l < num_loops; ++l) {
        std::vector<Piece> refined;
        for (Piece& p : pieces[static_cast<size_t>(l)]) {
          if (halve[static_cast<size_t>(k++)]) {
            auto [left, right] = Halve(p);
            refined.push_back(std::move(left));
            refined.push_back(std::move(right));
          } else {
            refined.push_back(std::move(p));
          }
        }
        pieces[static_cast<size_t>(l)] = std::move(refined);
      }
    }
  };
  certify();
  // 5. Orientation (of loops now known to be simple): the material on the left, outer
  //    counter-clockwise and holes clockwise. A reversed loop is cut and certified again.
  bool reversed = false;
  for (int l = 0; l < num_loops; ++l) {
    const double area = SignedArea(pieces[static_cast<size_t>(l)]);
    if (!(std::abs(area) > gap_allowed * diagonal)) {
      throw TrimError("trim: " + LoopName(l) + " encloses no area (signed area " + Num(area) + ")");
    }
    const bool outer_loop = has_outer_ && l == 0;
    if ((area > 0.0) != outer_loop) {
      Reverse(&loops_[static_cast<size_t>(l)]);
      polygonize(l);
      reversed = true;
      if (warnings) {
        warnings->push_back("trim: " + LoopName(l) + " ran " +
                            (outer_loop ? "clockwise" : "counter-clockwise") +
                            "; reversed (an outer loop runs counter-clockwise, a hole clockwise)");
      }
    }
  }
  if (reversed) certify();

  // 6. Nesting (no crossings now): holes inside the outer loop, not inside one another.
  auto inside_loop = [&](int l, const Eigen::Vector2d& x) {
    return Side(l, x) != CGAL::ON_UNBOUNDED_SIDE;
  };
  const int first_hole = has_outer_ ? 1 : 0;
  for (int h = first_hole; h < num_loops; ++h) {
    const Eigen::Vector2d x =
        chords_[static_cast<size_t>(loop_chords_[static_cast<size_t>(h)][0])].a;
    if (has_outer_ && !inside_loop(0, x)) {
      throw TrimError("trim: " + LoopName(h) + " is not inside the outer loop (it passes " + Pt(x) +
                      ")");
    }
    for (int other = first_hole; other < num_loops; ++other) {
      if (other != h && inside_loop(other, x)) {
        throw TrimError("trim: " + LoopName(h) + " lies inside " + LoopName(other));
      }
    }
  }
}

int TrimmedDomain::Side(int loop, const Eigen::Vector2d& uv) const {
  // The winding number of the loop's chords about uv with CGAL's exact orientation predicate
  // (the y comparisons are exact on doubles): the exact answer for the polygon of the chords'
  // double vertices, allocation free.
  // Outside the box of the polygon's vertices: outside the polygon (no predicate needed).
  const LoopBox& box = loop_box_[static_cast<size_t>(loop)];
  if (!box.Holds(uv, 0.0)) return CGAL::ON_UNBOUNDED_SIDE;
  if (box.rectangle) {  // inside the box: on a side, or within (the polygon is the box)
    return (uv.array() == box.lo.array()).any() || (uv.array() == box.hi.array()).any()
               ? CGAL::ON_BOUNDARY
               : CGAL::ON_BOUNDED_SIDE;
  }
  const P2 p = ToP2(uv);
  int winding = 0;
  for (int c : loop_chords_[static_cast<size_t>(loop)]) {
    const Chord& e = chords_[static_cast<size_t>(c)];
    const P2 a = ToP2(e.a), b = ToP2(e.b);
    const CGAL::Orientation o = CGAL::orientation(a, b, p);
    if (o == CGAL::COLLINEAR && std::min(e.a[0], e.b[0]) <= uv[0] &&
        uv[0] <= std::max(e.a[0], e.b[0]) && std::min(e.a[1], e.b[1]) <= uv[1] &&
        uv[1] <= std::max(e.a[1], e.b[1])) {
      return CGAL::ON_BOUNDARY;
    }
    if (e.a[1] <= uv[1]) {
      if (e.b[1] > uv[1] && o == CGAL::LEFT_TURN) ++winding;
    } else if (e.b[1] <= uv[1] && o == CGAL::RIGHT_TURN) {
      --winding;
    }
  }
  return winding != 0 ? CGAL::ON_BOUNDED_SIDE : CGAL::ON_UNBOUNDED_SIDE;
}

bool TrimmedDomain::PolygonContains(const Eigen::Vector2d& uv, int* excluded_by) const {
  for (int l = 0; l < static_cast<int>(loops_.size()); ++l) {
    const int side = Side(l, uv);
    const bool excluded =
        has_outer_ && l == 0 ? side == CGAL::ON_UNBOUNDED_SIDE : side == CGAL::ON_BOUNDED_SIDE;
    if (excluded) {
      if (excluded_by) *excluded_by = l;
      return false;
    }
  }
  return true;
}

bool TrimmedDomain::Contains(const Eigen::Vector2d& uv, Closest* nearest, double* clearance,
                             int* excluded_by) const {
  if (nearest) nearest->loop = -1;
  if (clearance) *clearance = 0.0;
  if (excluded_by) *excluded_by = -1;
  if (!uv.allFinite()) return false;
  if ((uv.array() < lo_.array()).any() || (uv.array() > hi_.array()).any()) return false;
  // A lower bound of min over chords (distance − band) and of the distance to the domain's
  // border: how far uv may move before any of them could change the answer.
  double clear = std::min((uv - lo_).minCoeff(), (hi_ - uv).minCoeff());
  for (int l = 0; l < static_cast<int>(loops_.size()); ++l) {
    const LoopBox& box = loop_box_[static_cast<size_t>(l)];
    if (!box.Holds(uv, box.band)) {  // farther than any of its chords' bands
      const Eigen::Vector2d out =
          (box.lo - uv).cwiseMax(uv - box.hi).cwiseMax(Eigen::Vector2d::Zero());
      clear = std::min(clear, out.norm() - box.band);
      continue;
    }
    if (box.rectangle) {
      const double sides = std::min((uv - box.lo).minCoeff(), (box.hi - uv).minCoeff());
      if (sides > box.band) {  // inside, farther from every side than any chord's band
        clear = std::min(clear, sides - box.band);
        continue;
      }
    }
    for (int k : loop_chords_[static_cast<size_t>(l)]) {
      const Chord& c = chords_[static_cast<size_t>(k)];
      const double d = PointSegmentDistance(uv, c.a, c.b);
      if (d <= c.band) {
        const Closest near = Nearest(uv);
        if (nearest) *nearest = near;
        return near.signed_distance >= 0.0;
      }
      clear = std::min(clear, d - c.band);
    }
  }
  if (clearance) *clearance = std::max(0.0, clear);
  return PolygonContains(uv, excluded_by);
}

TrimmedDomain::Closest TrimmedDomain::RefineOn(int loop, int curve, double t,
                                               const Eigen::Vector2d& uv) const {
  // The minimum of ½|C(t) − p|² over the curve: safeguarded Newton on its derivative
  // g(t) = C'·(C − p), within a bracket where g changes sign, else the better end.
  const NurbsCurve2d& f = loops_[static_cast<size_t>(loop)].curves[static_cast<size_t>(curve)];
  const double t_lo = f.knots().domain_begin(), t_hi = f.knots().domain_end();
  auto g = [&](double s) {
    const CurvePoint<2> c = f.Evaluate(s, 1);
    return c.C1.dot(c.C - uv);
  };
  auto at = [&](double s) {
    const Eigen::Vector2d x = f.Evaluate(s, 0).C;
    return Closest{(x - uv).norm(), loop, curve, s, x};
  };
  // A bracket around t: widen by the local parameter scale until g changes sign or an end.
  double a = t, b = t;
  double step = 1e-3 * (t_hi - t_lo);
  double ga = g(a), gb = ga;
  while (ga > 0.0 && a > t_lo) {
    a = std::max(t_lo, a - step);
    ga = g(a);
    step *= 2.0;
  }
  step = 1e-3 * (t_hi - t_lo);
  while (gb < 0.0 && b < t_hi) {
    b = std::min(t_hi, b + step);
    gb = g(b);
    step *= 2.0;
  }
  Closest best = at(ga > 0.0 ? a : (gb < 0.0 ? b : t));
  if (ga <= 0.0 && gb >= 0.0 && b > a) {
    double s = std::clamp(t, a, b);
    for (int k = 0; k < 60 && b - a > 1e-16 * (1.0 + std::abs(s)); ++k) {
      const CurvePoint<2> c = f.Evaluate(s, 2);
      const double gs = c.C1.dot(c.C - uv);
      if (gs == 0.0) break;
      (gs < 0.0 ? a : b) = s;
      const double h = c.C2.dot(c.C - uv) + c.C1.squaredNorm();
      const double newton = h > 0.0 ? s - gs / h : 0.5 * (a + b);
      s = newton > a && newton < b ? newton : 0.5 * (a + b);
    }
    const Closest c = at(s);
    if (c.signed_distance < best.signed_distance) best = c;
  }
  for (double end : {t_lo, t_hi}) {  // (an end may be closer than the bracketed minimum)
    const Closest c = at(end);
    if (c.signed_distance < best.signed_distance) best = c;
  }
  return best;  // (signed_distance holds the unsigned distance here)
}

bool TrimmedDomain::OnMaterialSide(const Closest& c, const Eigen::Vector2d& uv) const {
  const std::vector<NurbsCurve2d>& curves = loops_[static_cast<size_t>(c.loop)].curves;
  const NurbsCurve2d& f = curves[static_cast<size_t>(c.curve)];
  const Eigen::Vector2d r = uv - c.point;
  if (r.squaredNorm() == 0.0) return true;  // on the boundary: material
  const double t_lo = f.knots().domain_begin(), t_hi = f.knots().domain_end();
  const double eps = 1e-9 * (t_hi - t_lo);
  const int n = static_cast<int>(curves.size());
  // The incoming and outgoing tangents at the closest point: equal on a smooth stretch; at a
  // corner (between two curves, or a C⁰ knot inside one: a polyline's vertex) the material is
  // left of both at a convex corner and left of either at a reflex one.
  Eigen::Vector2d t_in, t_out;
  if (c.t <= t_lo + eps) {
    const NurbsCurve2d& in = curves[static_cast<size_t>((c.curve + n - 1) % n)];
    t_in = in.Evaluate(in.knots().domain_end(), 1).C1;
    t_out = f.Evaluate(t_lo, 1).C1;
  } else if (c.t >= t_hi - eps) {
    const NurbsCurve2d& out = curves[static_cast<size_t>((c.curve + 1) % n)];
    t_in = f.Evaluate(t_hi, 1).C1;
    t_out = out.Evaluate(out.knots().domain_begin(), 1).C1;
  } else {
    t_in = t_out = f.Evaluate(c.t, 1).C1;
    for (double knot : f.knots().knots()) {  // (the stored knots: no allocation)
      if (knot > t_lo && knot < t_hi && std::abs(knot - c.t) <= eps &&
          f.knots().Multiplicity(knot) >= f.degree()) {
        t_in = f.Evaluate(knot - eps, 1).C1;
        t_out = f.Evaluate(knot, 1).C1;  // (a knot evaluates on its right span)
      }
    }
  }
  const bool left_in = Cross(t_in, r) >= 0.0, left_out = Cross(t_out, r) >= 0.0;
  return Cross(t_in, t_out) >= 0.0 ? (left_in && left_out) : (left_in || left_out);
}

TrimmedDomain::Closest TrimmedDomain::Nearest(const Eigen::Vector2d& uv) const {
  Closest best;
  best.signed_distance = std::numeric_limits<double>::infinity();
  if (chords_.empty() || !uv.allFinite()) return best;
  // The closest curve point of a chord's piece lies within its band of the chord's distance:
  // only chords that can beat the best upper bound are refined on the curve.
  // (Two passes over the chords, the distances computed again in the second: no allocation.)
  double bound = std::numeric_limits<double>::infinity();
  for (const Chord& c : chords_) {
    bound = std::min(bound, PointSegmentDistance(uv, c.a, c.b) + c.band);
  }
  double nearest = std::numeric_limits<double>::infinity();
  for (const Chord& c : chords_) {
    double s = 0.0;
    if (PointSegmentDistance(uv, c.a, c.b, &s) - c.band > bound) continue;
    const Closest r = RefineOn(c.loop, c.curve, c.t0 + s * (c.t1 - c.t0), uv);
    if (r.signed_distance < nearest) {
      nearest = r.signed_distance;
      best = r;
    }
  }
  best.signed_distance = OnMaterialSide(best, uv) ? nearest : -nearest;
  return best;
}

bool TrimmedDomain::MayHoldMaterial(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const {
  // Each chord's piece of curve lies within its band of the chord, so within the chord's box
  // grown by the band: a rectangle no such box meets is crossed by no loop, and lies wholly on
  // the side of its centre.
  for (const Chord& c : chords_) {
    const Eigen::Vector2d c_lo = c.a.cwiseMin(c.b).array() - c.band;
    const Eigen::Vector2d c_hi = c.a.cwiseMax(c.b).array() + c.band;
    if ((c_lo.array() <= hi.array()).all() && (lo.array() <= c_hi.array()).all()) return true;
  }
  return Contains(0.5 * (lo + hi));
}

TriangleMesh CutAlongTrim(const TriangleMesh& mesh, const TrimmedDomain& trim) {
  TriangleMesh out = mesh;
  out.triangles.clear();
  out.cells.clear();
  const int nv = std::max(1, static_cast<int>(mesh.v_lines.size()) - 1);
  std::vector<signed char> keep(
      static_cast<size_t>(nv) * std::max<size_t>(1, mesh.u_lines.size() - 1), -1);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int cell = mesh.CellOf(static_cast<int>(t));
    signed char& k = keep[static_cast<size_t>(cell)];
    if (k < 0) {
      const size_t i = static_cast<size_t>(cell / nv), j = static_cast<size_t>(cell % nv);
      k = trim.MayHoldMaterial({mesh.u_lines[i], mesh.v_lines[j]},
                               {mesh.u_lines[i + 1], mesh.v_lines[j + 1]})
              ? 1
              : 0;
    }
    if (!k) continue;
    out.triangles.push_back(mesh.triangles[t]);
    out.cells.push_back(cell);
  }
  return out;
}

}  // namespace tangent::nurbs
