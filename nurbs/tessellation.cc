#include "nurbs/tessellation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nurbs/basis.h"

namespace tangent::nurbs {

namespace {

struct CellBound {
  double bound;
  double curvature_u;  // largest second difference of the net along u
  double curvature_v;  // and along v
};

// Cartesian Bezier net of the surface restricted to [u0,u1] x [v0,v1] (inside one span in each
// direction): P_ab = blossom(u0^{p−a} u1^a ; v0^{q−b} v1^b), projected by its weight.
CellBound BoundCell(const NurbsSurface& s, double u0, double u1, double v0, double v1) {
  const KnotVector& ku = s.knots_u();
  const KnotVector& kv = s.knots_v();
  const int p = ku.degree(), q = kv.degree();
  const int mu = ku.FindSpan(0.5 * (u0 + u1));
  const int nu = kv.FindSpan(0.5 * (v0 + v1));
  std::array<double, kMaxDegree + 1> ru[kMaxDegree + 1], rv[kMaxDegree + 1];
  double x[kMaxDegree];
  for (int a = 0; a <= p; ++a) {
    for (int r = 0; r < p; ++r) x[r] = r < p - a ? u0 : u1;
    OsloAlphaRow(ku, mu, x, &ru[a]);
  }
  for (int b = 0; b <= q; ++b) {
    for (int r = 0; r < q; ++r) x[r] = r < q - b ? v0 : v1;
    OsloAlphaRow(kv, nu, x, &rv[b]);
  }
  Eigen::Vector3d net[kMaxDegree + 1][kMaxDegree + 1];
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      Eigen::Vector4d acc = Eigen::Vector4d::Zero();
      for (int i = 0; i <= p; ++i) {
        for (int j = 0; j <= q; ++j) {
          acc += ru[a][static_cast<size_t>(i)] * rv[b][static_cast<size_t>(j)] *
                 s.weighted_point(mu - p + i, nu - q + j);
        }
      }
      net[a][b] = acc.head<3>() / acc[3];
    }
  }
  const Eigen::Vector3d& c00 = net[0][0];
  const Eigen::Vector3d& c10 = net[p][0];
  const Eigen::Vector3d& c01 = net[0][q];
  const Eigen::Vector3d& c11 = net[p][q];
  const Eigen::Vector3d twist = c00 - c10 - c01 + c11;
  CellBound out{0.0, 0.0, 0.0};
  double flat = 0.0;
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      const double x_a = static_cast<double>(a) / p;
      const double y_b = static_cast<double>(b) / q;
      const Eigen::Vector3d l = (1 - x_a) * (1 - y_b) * c00 + x_a * (1 - y_b) * c10 +
                                (1 - x_a) * y_b * c01 + x_a * y_b * c11;
      flat = std::max(flat, (net[a][b] - l).norm());
      if (a >= 1 && a < p) {
        out.curvature_u =
            std::max(out.curvature_u, (net[a + 1][b] - 2.0 * net[a][b] + net[a - 1][b]).norm());
      }
      if (b >= 1 && b < q) {
        out.curvature_v =
            std::max(out.curvature_v, (net[a][b + 1] - 2.0 * net[a][b] + net[a][b - 1]).norm());
      }
    }
  }
  // With only a twist left (bilinear cell), halve the direction with the longer edges.
  if (out.curvature_u == 0.0 && out.curvature_v == 0.0) {
    out.curvature_u = (c10 - c00).norm() + (c11 - c01).norm();
    out.curvature_v = (c01 - c00).norm() + (c11 - c10).norm();
  }
  out.bound = flat + 0.5 * twist.norm();
  return out;
}

}  // namespace

TriangleMesh Tessellate(const NurbsSurface& surface, double tolerance, int max_lines,
                        double max_edge) {
  if (!(tolerance > 0.0)) throw std::invalid_argument("tessellate: tolerance must be positive");
  if (!(max_edge >= 0.0)) throw std::invalid_argument("tessellate: max_edge must not be negative");
  std::vector<double> us = surface.knots_u().Breakpoints();
  std::vector<double> vs = surface.knots_v().Breakpoints();
  // A cell must not exceed ~quarter turns of a circle for the flatness to fall fast; start with
  // at least 4 intervals per direction.
  auto densify = [](std::vector<double>* lines, int at_least) {
    while (static_cast<int>(lines->size()) - 1 < at_least) {
      std::vector<double> out;
      for (size_t i = 0; i + 1 < lines->size(); ++i) {
        out.push_back((*lines)[i]);
        out.push_back(0.5 * ((*lines)[i] + (*lines)[i + 1]));
      }
      out.push_back(lines->back());
      *lines = std::move(out);
    }
  };
  densify(&us, 4);
  densify(&vs, 4);
  double worst = 0.0;
  for (;;) {
    const size_t nu = us.size() - 1, nv = vs.size() - 1;
    std::vector<char> split_u(nu, 0), split_v(nv, 0);
    worst = 0.0;
    bool any = false;
    for (size_t i = 0; i < nu; ++i) {
      for (size_t j = 0; j < nv; ++j) {
        const CellBound c = BoundCell(surface, us[i], us[i + 1], vs[j], vs[j + 1]);
        worst = std::max(worst, c.bound);
        if (c.bound > tolerance) {
          any = true;
          (c.curvature_u >= c.curvature_v ? split_u[i] : split_v[j]) = 1;
        }
        if (max_edge > 0.0) {
          const Eigen::Vector3d s00 = surface.Evaluate(us[i], vs[j], 0).S;
          const Eigen::Vector3d s10 = surface.Evaluate(us[i + 1], vs[j], 0).S;
          const Eigen::Vector3d s01 = surface.Evaluate(us[i], vs[j + 1], 0).S;
          const Eigen::Vector3d s11 = surface.Evaluate(us[i + 1], vs[j + 1], 0).S;
          if (std::max((s10 - s00).norm(), (s11 - s01).norm()) > max_edge) {
            split_u[i] = 1;
            any = true;
          }
          if (std::max((s01 - s00).norm(), (s11 - s10).norm()) > max_edge) {
            split_v[j] = 1;
            any = true;
          }
        }
      }
    }
    const bool room_u = static_cast<int>(us.size()) < max_lines;
    const bool room_v = static_cast<int>(vs.size()) < max_lines;
    if (!any || (!room_u && !room_v)) break;
    auto apply = [](std::vector<double>* lines, const std::vector<char>& split) {
      std::vector<double> out;
      for (size_t i = 0; i + 1 < lines->size(); ++i) {
        out.push_back((*lines)[i]);
        if (split[i]) out.push_back(0.5 * ((*lines)[i] + (*lines)[i + 1]));
      }
      out.push_back(lines->back());
      *lines = std::move(out);
    };
    if (room_u) apply(&us, split_u);
    if (room_v) apply(&vs, split_v);
  }
  TriangleMesh mesh;
  mesh.error_bound = worst;
  const int nu = static_cast<int>(us.size()), nv = static_cast<int>(vs.size());
  SpanHint hint;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      SurfacePoint sp;
      surface.Evaluate<0>(us[static_cast<size_t>(i)], vs[static_cast<size_t>(j)], &hint, &sp);
      mesh.vertices.push_back(sp.S);
      mesh.uv.emplace_back(us[static_cast<size_t>(i)], vs[static_cast<size_t>(j)]);
    }
  }
  for (int i = 0; i + 1 < nu; ++i) {
    for (int j = 0; j + 1 < nv; ++j) {
      const int a = i * nv + j, b = (i + 1) * nv + j, c = (i + 1) * nv + j + 1, d = i * nv + j + 1;
      mesh.triangles.push_back({a, b, c});  // Split along the (0,0)–(1,1) diagonal of the cell.
      mesh.triangles.push_back({a, c, d});
    }
  }
  mesh.u_lines = std::move(us);
  mesh.v_lines = std::move(vs);
  return mesh;
}

double DistanceToCell(const TriangleMesh& mesh, double u, double v, const Eigen::Vector3d& x) {
  auto cell = [](const std::vector<double>& lines, double t) {
    const auto it = std::upper_bound(lines.begin(), lines.end(), t);
    return std::clamp(static_cast<int>(it - lines.begin()) - 1, 0,
                      static_cast<int>(lines.size()) - 2);
  };
  const int i = cell(mesh.u_lines, u);
  const int j = cell(mesh.v_lines, v);
  const int nv = static_cast<int>(mesh.v_lines.size());
  const auto& p = mesh.vertices;
  const size_t a = static_cast<size_t>(i * nv + j), b = static_cast<size_t>((i + 1) * nv + j);
  const size_t c = b + 1, d = a + 1;
  // The same (0,0)–(1,1) diagonal split as Tessellate's triangles.
  return std::min(PointTriangleDistance(x, p[a], p[b], p[c]),
                  PointTriangleDistance(x, p[a], p[c], p[d]));
}

double PointTriangleDistance(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Ericson, Real-Time Collision Detection §5.1.5: classify x against the Voronoi regions.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (x - a).norm();
  const Eigen::Vector3d bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (x - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (x - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (x - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (x - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return (x - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);
  if (!std::isfinite(denom)) {  // Degenerate (zero-area) triangle: nearest of its edges.
    auto seg = [&](const Eigen::Vector3d& p0, const Eigen::Vector3d& p1) {
      const Eigen::Vector3d e = p1 - p0;
      const double l2 = e.squaredNorm();
      const double t = l2 > 0 ? std::clamp((x - p0).dot(e) / l2, 0.0, 1.0) : 0.0;
      return (x - (p0 + t * e)).norm();
    };
    return std::min({seg(a, b), seg(b, c), seg(c, a)});
  }
  return (x - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

}  // namespace tangent::nurbs
