// A face's trimming loops within the file's tolerances (face_loops.h).

#include "cad/face_loops.h"

#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace tangent::cad {

namespace {

using nurbs::NurbsCurve2d;

std::string Num(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

// A pcurve over [first, last] as our 2-D curve, reversed for a reversed edge, with u mirrored
// about the domain's middle when the face's u is flipped.
NurbsCurve2d ToCurve(const Handle(Geom2d_Curve) & pc, double first, double last, bool reversed,
                     bool flip_u, double u_sum) {
  Handle(Geom2d_BSplineCurve) b =
      Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pc, first, last));
  if (b->IsPeriodic()) b->SetNotPeriodic();
  if (reversed) b->Reverse();
  TColStd_Array1OfReal k(1, b->NbPoles() + b->Degree() + 1);
  b->KnotSequence(k);
  std::vector<Eigen::Vector2d> points;
  std::vector<double> weights;
  for (int i = 1; i <= b->NbPoles(); ++i) {
    const gp_Pnt2d p = b->Pole(i);
    points.emplace_back(flip_u ? u_sum - p.X() : p.X(), p.Y());
    if (b->IsRational()) weights.push_back(b->Weight(i));
  }
  return NurbsCurve2d(nurbs::KnotVector(b->Degree(), std::vector<double>(k.begin(), k.end())),
                      points, weights);
}

// The same curve run the other way.
NurbsCurve2d Reversed(const NurbsCurve2d& c) {
  std::vector<NurbsCurve2d::HPoint> cpw = c.weighted_points();
  std::reverse(cpw.begin(), cpw.end());
  const std::vector<double>& k = c.knots().knots();
  std::vector<double> r(k.size());
  for (size_t i = 0; i < k.size(); ++i) r[i] = k.front() + k.back() - k[k.size() - 1 - i];
  return NurbsCurve2d::FromHomogeneous(nurbs::KnotVector(c.knots().degree(), r), std::move(cpw));
}

Eigen::Vector2d Start(const NurbsCurve2d& c) { return c.Evaluate(c.knots().domain_begin(), 0).C; }
Eigen::Vector2d End(const NurbsCurve2d& c) { return c.Evaluate(c.knots().domain_end(), 0).C; }

// The curve with every control point mapped by `f` (Cartesian in, Cartesian out).
template <typename F>
NurbsCurve2d MapPoints(const NurbsCurve2d& c, F f) {
  std::vector<NurbsCurve2d::HPoint> cpw = c.weighted_points();
  for (NurbsCurve2d::HPoint& h : cpw) h.head<2>() = f(Eigen::Vector2d(h.head<2>() / h[2])) * h[2];
  return NurbsCurve2d::FromHomogeneous(c.knots(), std::move(cpw));
}

// Parameters at which a curve is measured: eight per knot span and the ends.
std::vector<double> Samples(const NurbsCurve2d& c) {
  std::vector<double> t;
  const std::vector<double>& k = c.knots().knots();
  for (size_t i = 0; i + 1 < k.size(); ++i) {
    if (k[i + 1] <= k[i] || k[i] < c.knots().domain_begin() || k[i + 1] > c.knots().domain_end())
      continue;
    for (int s = 0; s < 8; ++s) t.push_back(k[i] + (k[i + 1] - k[i]) * s / 8.0);
  }
  t.push_back(c.knots().domain_end());
  return t;
}

class Loops {
 public:
  Loops(const Handle(Geom_BSplineSurface) & bs, bool flip_u, const nurbs::NurbsSurface& surface)
      : bs_(bs),
        flip_u_(flip_u),
        lo_(surface.knots_u().domain_begin(), surface.knots_v().domain_begin()),
        hi_(surface.knots_u().domain_end(), surface.knots_v().domain_end()),
        diagonal_((hi_ - lo_).norm()) {
    // A direction is closed (its period may be given either way round) when the surface's two
    // boundaries across it coincide.
    for (int d = 0; d < 2; ++d) {
      double apart = 0.0, size = 0.0;
      for (int j = 0; j <= 8; ++j) {
        const double s = lo_[1 - d] + (hi_[1 - d] - lo_[1 - d]) * j / 8.0;
        Eigen::Vector2d a = lo_, b = hi_;
        a[1 - d] = b[1 - d] = s;
        const Eigen::Vector3d pa = Point(a), pb = Point(b);
        apart = std::max(apart, (pa - pb).norm());
        size = std::max({size, pa.norm(), pb.norm()});
      }
      closed_[d] = apart <= 1e-9 * std::max(size, 1e-3);
    }
  }

  // The surface's point at p, extended past its domain as Open CASCADE's B-spline does (the
  // polynomial of its last span).
  Eigen::Vector3d Point(const Eigen::Vector2d& p) const {
    const gp_Pnt x = bs_->Value(flip_u_ ? lo_[0] + hi_[0] - p[0] : p[0], p[1]);
    return {x.X(), x.Y(), x.Z()};
  }

  // An edge's pcurve, one period over where the surface is closed and that brings it into the
  // domain, then clamped into the domain if it leaves it by no more than `tolerance` in space.
  NurbsCurve2d IntoDomain(NurbsCurve2d c, double tolerance, FaceLoops::Repairs* repairs) {
    for (int d = 0; d < 2; ++d) {
      if (!closed_[d]) continue;
      const double period = hi_[d] - lo_[d];
      auto outside = [&](double shift) {
        double worst = 0.0;
        for (const NurbsCurve2d::HPoint& h : c.weighted_points()) {
          const double x = h[d] / h[2] + shift;
          worst = std::max({worst, lo_[d] - x, x - hi_[d]});
        }
        return worst;
      };
      double best = 0.0;
      for (double shift : {-period, period}) {
        if (outside(shift) < outside(best) - 1e-9 * period) best = shift;
      }
      if (best != 0.0) {
        c = MapPoints(c, [&](Eigen::Vector2d p) {
          p[d] += best;
          return p;
        });
        ++repairs->shifted;
      }
    }
    const NurbsCurve2d clamped =
        MapPoints(c, [&](const Eigen::Vector2d& p) { return p.cwiseMax(lo_).cwiseMin(hi_); });
    double leaves = 0.0, moved = 0.0;
    for (double t : Samples(c)) {
      const Eigen::Vector2d p = c.Evaluate(t, 0).C, q = clamped.Evaluate(t, 0).C;
      leaves = std::max({leaves, (lo_ - p).maxCoeff(), (p - hi_).maxCoeff()});
      moved = std::max(moved, (Point(p) - Point(q)).norm());
    }
    if (leaves <= 1e-12 * diagonal_) {
      // Inside (at most its control polygon is not): as it is, unless clamping moves it by
      // nothing that matters (then the polygon is inside too, which the trim's check likes).
      return moved <= 1e-3 * tolerance ? clamped : c;
    }
    if (moved > tolerance) {
      throw std::runtime_error("an edge's pcurve leaves the surface's domain by " + Num(leaves) +
                               " in the face's parameters, " + Num(moved) +
                               " m in space, beyond the edge's tolerance " + Num(tolerance) + " m");
    }
    ++repairs->clamped;
    repairs->clamped_by = std::max(repairs->clamped_by, moved);
    return clamped;
  }

  // Makes consecutive curves meet: ends a little apart (within `tolerance` in space) are moved to
  // their middle; ends apart in the parameters but together in space (across a pole, along a
  // collapsed edge) are joined by a straight piece whose image stays within `tolerance`.
  void Close(std::vector<NurbsCurve2d>* curves, const std::vector<double>& tolerance,
             FaceLoops::Repairs* repairs) const {
    std::vector<NurbsCurve2d> out;
    std::vector<std::pair<size_t, NurbsCurve2d>> joins;  // pieces of their own, after curve i
    const size_t n = curves->size();
    std::vector<NurbsCurve2d> c = *curves;
    for (size_t i = 0; i < n; ++i) {
      NurbsCurve2d& a = c[i];
      NurbsCurve2d& b = c[(i + 1) % n];
      const Eigen::Vector2d pa = End(a), pb = Start(b);
      const double gap = (pa - pb).norm();
      if (gap == 0.0) continue;
      const Eigen::Vector3d xa = Point(pa);
      double apart = 0.0;  // the straight piece's image, from the first end's point
      for (int s = 1; s <= 16; ++s) {
        apart = std::max(apart, (Point(pa + (pb - pa) * (s / 16.0)) - xa).norm());
      }
      const double tol = tolerance[i];
      if (gap > 1e-6 * diagonal_ && apart > tol) {
        throw std::runtime_error(
            "a wire's pcurves leave a gap of " + Num(gap) + " in the face's parameters, " +
            Num(apart) + " m in space, beyond the file's tolerance " + Num(tol) + " m there");
      }
      if (gap > 1e-3 * diagonal_) {
        // A piece of its own: moving the ends would bend the curves.
        ++repairs->joined;
        joins.push_back({i, NurbsCurve2d(nurbs::KnotVector(1, {0.0, 0.0, 1.0, 1.0}),
                                         std::vector<Eigen::Vector2d>{pa, pb}, {})});
      } else {
        const Eigen::Vector2d mid = 0.5 * (pa + pb);
        auto set_end = [](NurbsCurve2d* curve, bool last, const Eigen::Vector2d& p) {
          std::vector<NurbsCurve2d::HPoint> cpw = curve->weighted_points();
          NurbsCurve2d::HPoint& h = last ? cpw.back() : cpw.front();
          h.head<2>() = p * h[2];
          *curve = NurbsCurve2d::FromHomogeneous(curve->knots(), std::move(cpw));
        };
        set_end(&a, true, mid);
        set_end(&b, false, mid);
      }
      if (gap > 1e-6 * diagonal_) {
        ++repairs->gaps;
        repairs->gaps_by = std::max(repairs->gaps_by, apart);
      }
    }
    for (size_t i = 0; i < n; ++i) {
      out.push_back(c[i]);
      for (const auto& [after, piece] : joins) {
        if (after == i) out.push_back(piece);
      }
    }
    *curves = std::move(out);
  }

 private:
  Handle(Geom_BSplineSurface) bs_;
  bool flip_u_;
  Eigen::Vector2d lo_, hi_;
  double diagonal_;
  bool closed_[2] = {false, false};
};

// The largest tolerance of an edge and its vertices.
double ToleranceOf(const TopoDS_Edge& edge) {
  double tol = BRep_Tool::Tolerance(edge);
  TopoDS_Vertex first, last;
  TopExp::Vertices(edge, first, last);
  for (const TopoDS_Vertex& v : {first, last}) {
    if (!v.IsNull()) tol = std::max(tol, BRep_Tool::Tolerance(v));
  }
  return tol;
}

}  // namespace

std::string FaceLoops::Repairs::Describe() const {
  std::string out;
  auto add = [&out](int n, const std::string& what, const std::string& more) {
    if (n == 0) return;
    out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what + (n == 1 ? "" : "s") + more;
  };
  add(clamped, "pcurve", " clamped into the domain (by up to " + Num(clamped_by) + " m)");
  add(shifted, "pcurve", " moved by a period");
  add(gaps, "gap",
      " closed (up to " + Num(gaps_by) + " m" +
          (joined ? ", " + std::to_string(joined) + " by a piece of its own" : "") + ")");
  return out;
}

FaceLoops BuildFaceLoops(const TopoDS_Face& face, const Handle(Geom_BSplineSurface) & bs,
                         bool flip_u, const nurbs::NurbsSurface& surface) {
  FaceLoops out;
  Loops loops(bs, flip_u, surface);
  const double u_sum = surface.knots_u().domain_begin() + surface.knots_u().domain_end();
  const TopoDS_Wire outer_wire = BRepTools::OuterWire(face);
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) {
    const TopoDS_Wire wire = TopoDS::Wire(w.Current());
    // The wire's edges as stored, each pcurve in its edge's direction (and the other way
    // round), chained by their end points in the face's parameters: an edge whose end meets the
    // chain better than its start is taken reversed. (BRepTools_WireExplorer dropped an edge of
    // an IGES cylinder's seamed wire, and that wire's circles came with their orientation flags
    // opposite to their pcurves.) The loop's sense is TrimmedDomain's to check.
    struct Edge {
      NurbsCurve2d forward, backward;
      double tolerance;
    };
    std::vector<Edge> edges;
    for (TopExp_Explorer e(wire, TopAbs_EDGE); e.More(); e.Next()) {
      const TopoDS_Edge edge = TopoDS::Edge(e.Current());
      double first = 0.0, last = 0.0;
      const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, first, last);
      if (pc.IsNull()) throw std::runtime_error("an edge has no curve on the face");
      const bool rev = edge.Orientation() == TopAbs_REVERSED;
      const double tol = ToleranceOf(edge);
      NurbsCurve2d forward =
          loops.IntoDomain(ToCurve(pc, first, last, rev, flip_u, u_sum), tol, &out.repairs);
      NurbsCurve2d backward = Reversed(forward);
      edges.push_back({std::move(forward), std::move(backward), tol});
    }
    if (edges.empty()) continue;
    nurbs::TrimLoop loop;
    std::vector<double> tolerance;  // at the junction after each curve of the loop
    std::vector<bool> used(edges.size(), false);
    loop.curves.push_back(edges[0].forward);
    tolerance.push_back(edges[0].tolerance);
    used[0] = true;
    for (size_t k = 1; k < edges.size(); ++k) {
      const Eigen::Vector2d at = End(loop.curves.back());
      size_t best = 0;
      bool flip = false;
      double best_gap = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < edges.size(); ++i) {
        if (used[i]) continue;
        const double forward = (Start(edges[i].forward) - at).norm();
        const double backward = (Start(edges[i].backward) - at).norm();
        if (forward < best_gap) best_gap = forward, best = i, flip = false;
        if (backward < best_gap) best_gap = backward, best = i, flip = true;
      }
      used[best] = true;
      tolerance.back() = std::max(tolerance.back(), edges[best].tolerance);
      loop.curves.push_back(flip ? edges[best].backward : edges[best].forward);
      tolerance.push_back(edges[best].tolerance);
    }
    tolerance.back() = std::max(tolerance.back(), tolerance.front());
    loops.Close(&loop.curves, tolerance, &out.repairs);
    if (wire.IsSame(outer_wire)) {
      out.outer = std::move(loop);
    } else {
      out.holes.push_back(std::move(loop));
    }
  }
  return out;
}

}  // namespace tangent::cad
