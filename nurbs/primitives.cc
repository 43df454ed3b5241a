#include "nurbs/primitives.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace tangent::nurbs {

namespace {

constexpr double kHalfSqrt2 = std::numbers::sqrt2 / 2.0;

// Full circle of radius r as a nine-point rational quadratic in local (a, b) coordinates.
struct CircleNet {
  std::vector<Eigen::Vector2d> points;
  std::vector<double> weights;
  std::vector<double> knots;
};

CircleNet UnitCircle(double r) {
  CircleNet c;
  const double pts[9][2] = {{1, 0},   {1, 1},  {0, 1},  {-1, 1}, {-1, 0},
                            {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
  for (int i = 0; i < 9; ++i) {
    c.points.emplace_back(r * pts[i][0], r * pts[i][1]);
    c.weights.push_back(i % 2 ? kHalfSqrt2 : 1.0);
  }
  c.knots = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
  return c;
}

// Profile point (radial distance rho, height z) revolved about +z through angle [phi0, phi1]
// (|phi1 − phi0| ≤ 90°): three homogeneous control points of the rational quadratic arc.
void RevolveArc(const Eigen::Vector3d& center, double rho, double z, double w, double phi0,
                double phi1, Eigen::Vector4d out[3]) {
  const double half = 0.5 * (phi1 - phi0);
  const double cos_half = std::cos(half);
  const double phim = phi0 + half;
  const Eigen::Vector3d p0 =
      center + Eigen::Vector3d(rho * std::cos(phi0), rho * std::sin(phi0), z);
  const Eigen::Vector3d p1 =
      center + Eigen::Vector3d(rho * std::cos(phim) / cos_half, rho * std::sin(phim) / cos_half, z);
  const Eigen::Vector3d p2 =
      center + Eigen::Vector3d(rho * std::cos(phi1), rho * std::sin(phi1), z);
  out[0] << w * p0, w;
  out[1] << w * cos_half * p1, w * cos_half;
  out[2] << w * p2, w;
}

// Surface of revolution about +z of a profile given in (rho, z) with weights, full turn.
NurbsSurface Revolve(const Eigen::Vector3d& center, const std::vector<Eigen::Vector2d>& profile,
                     const std::vector<double>& profile_weights, KnotVector profile_knots) {
  const int nv = static_cast<int>(profile.size());
  std::vector<Eigen::Vector4d> cpw(static_cast<size_t>(9 * nv));
  for (int quarter = 0; quarter < 4; ++quarter) {
    const double phi0 = quarter * std::numbers::pi / 2.0;
    const double phi1 = phi0 + std::numbers::pi / 2.0;
    for (int j = 0; j < nv; ++j) {
      Eigen::Vector4d arc[3];
      RevolveArc(center, profile[static_cast<size_t>(j)].x(), profile[static_cast<size_t>(j)].y(),
                 profile_weights[static_cast<size_t>(j)], phi0, phi1, arc);
      for (int k = 0; k < 3; ++k) cpw[static_cast<size_t>((2 * quarter + k) * nv + j)] = arc[k];
    }
  }
  KnotVector ku(2, UnitCircle(1.0).knots);
  return NurbsSurface::FromHomogeneous(std::move(ku), std::move(profile_knots), std::move(cpw));
}

std::vector<double> ClampedUniformKnots(int p, int n) {
  std::vector<double> k;
  for (int i = 0; i <= p; ++i) k.push_back(0.0);
  for (int i = 1; i < n - p; ++i) k.push_back(static_cast<double>(i) / (n - p));
  for (int i = 0; i <= p; ++i) k.push_back(1.0);
  return k;
}

double Greville(const std::vector<double>& k, int p, int i) {
  double s = 0.0;
  for (int r = 1; r <= p; ++r) s += k[static_cast<size_t>(i + r)];
  return s / p;
}

}  // namespace

NurbsSurface MakePlanePatch(const Eigen::Vector3d& origin, const Eigen::Vector3d& edge_u,
                            const Eigen::Vector3d& edge_v) {
  return NurbsSurface(KnotVector(1, {0, 0, 1, 1}), KnotVector(1, {0, 0, 1, 1}),
                      {origin, origin + edge_v, origin + edge_u, origin + edge_u + edge_v});
}

NurbsSurface MakeSphere(const Eigen::Vector3d& center, double radius) {
  if (!(radius > 0.0) || !std::isfinite(radius)) {
    throw std::invalid_argument("sphere: radius must be positive and finite");
  }
  // Semicircle from the south pole to the north pole in the (rho, z) half plane, two quarters.
  const std::vector<Eigen::Vector2d> profile = {
      {0, -radius}, {radius, -radius}, {radius, 0}, {radius, radius}, {0, radius}};
  const std::vector<double> w = {1, kHalfSqrt2, 1, kHalfSqrt2, 1};
  return Revolve(center, profile, w, KnotVector(2, {0, 0, 0, 0.5, 0.5, 1, 1, 1}));
}

NurbsSurface MakeCylinder(double radius, double height) {
  if (!(radius > 0.0) || !(height > 0.0)) {
    throw std::invalid_argument("cylinder: radius and height must be positive");
  }
  return Revolve(Eigen::Vector3d::Zero(), {{radius, 0.0}, {radius, height}}, {1.0, 1.0},
                 KnotVector(1, {0, 0, 1, 1}));
}

NurbsSurface MakeCone(double radius, double height) {
  if (!(radius > 0.0) || !(height > 0.0) || !std::isfinite(radius) || !std::isfinite(height)) {
    throw std::invalid_argument("cone: radius and height must be positive and finite");
  }
  return Revolve(Eigen::Vector3d::Zero(), {{0.0, 0.0}, {radius, height}}, {1.0, 1.0},
                 KnotVector(1, {0, 0, 1, 1}));
}

NurbsSurface MakeBarrel(double radius, double height, double crown) {
  if (!(radius > 0.0) || !(height > 0.0) || !std::isfinite(radius) || !std::isfinite(height)) {
    throw std::invalid_argument("barrel: radius and height must be positive");
  }
  const double half = 0.5 * height;
  if (!(crown > half) || !std::isfinite(crown)) {
    throw std::invalid_argument("barrel: crown radius must exceed half the height");
  }
  // The profile: one rational quadratic arc of the crown circle (centre radius − crown from the
  // axis, at mid-height) from z = 0 to z = height; the middle control point where the end
  // tangents meet, with weight cos of the half angle.
  const double centre = radius - crown;
  const double half_angle = std::asin(half / crown);
  const double end = centre + crown * std::cos(half_angle);
  if (!(end > 0.0)) throw std::invalid_argument("barrel: the ends would cross the axis");
  const double c = std::cos(half_angle);
  return Revolve(Eigen::Vector3d::Zero(), {{end, 0.0}, {centre + crown / c, half}, {end, height}},
                 {1.0, c, 1.0}, KnotVector(2, {0, 0, 0, 1, 1, 1}));
}

NurbsSurface MakeTorus(double major, double minor) {
  if (!(minor > 0.0) || !(major > minor)) {
    std::ostringstream os;
    os << "torus: need 0 < minor < major, got major = " << major << ", minor = " << minor;
    throw std::invalid_argument(os.str());
  }
  const CircleNet c = UnitCircle(minor);
  std::vector<Eigen::Vector2d> profile;
  for (const auto& p : c.points) profile.emplace_back(major + p.x(), p.y());
  return Revolve(Eigen::Vector3d::Zero(), profile, c.weights, KnotVector(2, c.knots));
}

NurbsSurface MakeTube(const std::vector<PathSegment>& path, double radius,
                      const Eigen::Vector2d& start, const Eigen::Vector2d& heading) {
  if (path.empty()) throw std::invalid_argument("tube: the path has no segments");
  if (!(radius > 0.0)) throw std::invalid_argument("tube: radius must be positive");
  const CircleNet section = UnitCircle(radius);
  const int nv = static_cast<int>(section.points.size());
  // Rows of homogeneous points along u (three per quadratic piece, shared ends) and the knots.
  std::vector<std::vector<Eigen::Vector4d>> rows;
  std::vector<double> piece_lengths;
  Eigen::Vector2d pos = start;
  Eigen::Vector2d dir = heading.normalized();
  for (size_t s = 0; s < path.size(); ++s) {
    const PathSegment& seg = path[s];
    if (seg.kind == PathSegment::Kind::kLine) {
      if (!(seg.length_or_radius > 0.0)) {
        throw std::invalid_argument("tube: segment " + std::to_string(s) +
                                    " is a line of non-positive length");
      }
      const Eigen::Vector2d end = pos + seg.length_or_radius * dir;
      const Eigen::Vector2d n(-dir.y(), dir.x());  // Left normal.
      std::vector<Eigen::Vector4d> r[3];
      const Eigen::Vector2d at[3] = {pos, 0.5 * (pos + end), end};
      for (int k = 0; k < 3; ++k) {
        for (int j = 0; j < nv; ++j) {
          const Eigen::Vector2d& a = section.points[static_cast<size_t>(j)];
          const double w = section.weights[static_cast<size_t>(j)];
          // −a.y: the section runs clockwise seen along the path, so S_u × S_v points outward.
          const Eigen::Vector3d x(at[k].x() + a.x() * n.x(), at[k].y() + a.x() * n.y(), -a.y());
          Eigen::Vector4d h;
          h << w * x, w;
          r[k].push_back(h);
        }
      }
      for (int k = (rows.empty() ? 0 : 1); k < 3; ++k) rows.push_back(r[k]);
      piece_lengths.push_back(seg.length_or_radius);
      pos = end;
    } else {
      const double big_r = seg.length_or_radius;
      if (!(big_r > radius)) {
        std::ostringstream os;
        os << "tube: arc segment " << s << " has radius " << big_r
           << ", not larger than the tube radius " << radius;
        throw std::invalid_argument(os.str());
      }
      if (seg.angle == 0.0 || !std::isfinite(seg.angle)) {
        throw std::invalid_argument("tube: arc segment " + std::to_string(s) + " has no angle");
      }
      const double sign = seg.angle > 0 ? 1.0 : -1.0;
      const Eigen::Vector2d n(-dir.y(), dir.x());
      const Eigen::Vector2d c2 = pos + sign * big_r * n;  // Centre on the turning side.
      const Eigen::Vector3d center(c2.x(), c2.y(), 0.0);
      double phi = std::atan2(pos.y() - c2.y(), pos.x() - c2.x());
      const int parts =
          static_cast<int>(std::ceil(std::abs(seg.angle) / (std::numbers::pi / 2) - 1e-12));
      const double step = seg.angle / parts;
      for (int part = 0; part < parts; ++part) {
        std::vector<Eigen::Vector4d> r[3];
        for (int j = 0; j < nv; ++j) {
          const Eigen::Vector2d& a = section.points[static_cast<size_t>(j)];
          // Left normal is −sign·radial, so the section point sits at rho = R − sign·a.
          const double rho = big_r - sign * a.x();
          Eigen::Vector4d arc[3];
          RevolveArc(center, rho, -a.y(), section.weights[static_cast<size_t>(j)], phi, phi + step,
                     arc);
          for (int k = 0; k < 3; ++k) r[k].push_back(arc[k]);
        }
        for (int k = (rows.empty() ? 0 : 1); k < 3; ++k) rows.push_back(r[k]);
        piece_lengths.push_back(big_r * std::abs(step));
        phi += step;
      }
      pos = c2 + big_r * Eigen::Vector2d(std::cos(phi), std::sin(phi));
      const double turn = seg.angle;
      dir = Eigen::Vector2d(std::cos(turn) * dir.x() - std::sin(turn) * dir.y(),
                            std::sin(turn) * dir.x() + std::cos(turn) * dir.y());
    }
  }
  // u knots: a double knot at every piece joint, spaced by arc length, normalized to [0, 1].
  double total = 0.0;
  for (double l : piece_lengths) total += l;
  std::vector<double> ku = {0, 0, 0};
  double acc = 0.0;
  for (size_t i = 0; i + 1 < piece_lengths.size(); ++i) {
    acc += piece_lengths[i];
    ku.push_back(acc / total);
    ku.push_back(acc / total);
  }
  ku.insert(ku.end(), {1, 1, 1});
  std::vector<Eigen::Vector4d> cpw;
  for (const auto& row : rows) cpw.insert(cpw.end(), row.begin(), row.end());
  return NurbsSurface::FromHomogeneous(KnotVector(2, std::move(ku)), KnotVector(2, section.knots),
                                       std::move(cpw));
}

std::vector<PathSegment> PaperclipPath() {
  const double mm = 1e-3;
  const double pi = std::numbers::pi;
  return {PathSegment::Line(16 * mm), PathSegment::Arc(2.5 * mm, pi),
          PathSegment::Line(22 * mm), PathSegment::Arc(3.25 * mm, pi),
          PathSegment::Line(25 * mm), PathSegment::Arc(4.0 * mm, pi),
          PathSegment::Line(16 * mm)};
}

NurbsSurface MakeHeightGridPatch(double x0, double y0, double lx, double ly,
                                 const std::vector<std::vector<double>>& heights) {
  const int nx = static_cast<int>(heights.size());
  if (nx < 4) throw std::invalid_argument("height grid: need at least 4 rows of heights");
  const int ny = static_cast<int>(heights[0].size());
  if (ny < 4) throw std::invalid_argument("height grid: need at least 4 heights per row");
  const std::vector<double> ku = ClampedUniformKnots(3, nx);
  const std::vector<double> kv = ClampedUniformKnots(3, ny);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < nx; ++i) {
    if (static_cast<int>(heights[static_cast<size_t>(i)].size()) != ny) {
      throw std::invalid_argument("height grid: row " + std::to_string(i) + " has " +
                                  std::to_string(heights[static_cast<size_t>(i)].size()) +
                                  " heights, row 0 has " + std::to_string(ny));
    }
    for (int j = 0; j < ny; ++j) {
      pts.emplace_back(x0 + lx * Greville(ku, 3, i), y0 + ly * Greville(kv, 3, j),
                       heights[static_cast<size_t>(i)][static_cast<size_t>(j)]);
    }
  }
  return NurbsSurface(KnotVector(3, ku), KnotVector(3, kv), pts);
}

NurbsSurface MakeShearedPatch(double angle, double size, double bump, bool rational) {
  const int n = 5;
  const std::vector<double> k = ClampedUniformKnots(3, n);
  const Eigen::Vector3d du(size, 0, 0);
  const Eigen::Vector3d dv(size * std::cos(angle), size * std::sin(angle), 0);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> w;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double gu = Greville(k, 3, i);
      const double gv = Greville(k, 3, j);
      // A smooth dome, zero on the border, so the shear dominates the partials' directions.
      const double h = bump * 16.0 * gu * (1 - gu) * gv * (1 - gv);
      pts.push_back(gu * du + gv * dv + Eigen::Vector3d(0, 0, h));
      if (rational) w.push_back(1.0 + 0.05 * std::sin(1.3 * i + 2.1 * j));
    }
  }
  return NurbsSurface(KnotVector(3, k), KnotVector(3, k), pts, w);
}

NurbsCurve2d MakeCircle2d(const Eigen::Vector2d& center, double radius, bool clockwise) {
  const double w = std::sqrt(0.5), s = clockwise ? -1.0 : 1.0;
  const double corners[9][2] = {{1, 0},   {1, 1},  {0, 1},  {-1, 1}, {-1, 0},
                                {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
  std::vector<Eigen::Vector2d> points;
  for (const auto& k : corners) points.push_back(center + radius * Eigen::Vector2d(k[0], s * k[1]));
  return NurbsCurve2d(KnotVector(2, {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1}), points,
                      {1, w, 1, w, 1, w, 1, w, 1});
}

NurbsCurve2d MakePolyline2d(const std::vector<Eigen::Vector2d>& points) {
  std::vector<double> knots{0.0};
  for (size_t i = 0; i < points.size(); ++i) knots.push_back(static_cast<double>(i));
  knots.push_back(points.empty() ? 0.0 : static_cast<double>(points.size() - 1));
  return NurbsCurve2d(KnotVector(1, knots), points);
}

NurbsSurface Transformed(const NurbsSurface& surface, const Eigen::Isometry3d& X) {
  std::vector<Eigen::Vector4d> cpw = surface.weighted_points();
  for (Eigen::Vector4d& h : cpw) {
    h.head<3>() = X.linear() * h.head<3>() + h[3] * X.translation();
  }
  return NurbsSurface::FromHomogeneous(surface.knots_u(), surface.knots_v(), std::move(cpw));
}

NurbsSurface ReversedU(const NurbsSurface& surface) {
  // S'(u, v) = S(a + b − u, v): knots mirrored about the domain's middle, rows in reverse.
  const KnotVector& k = surface.knots_u();
  const double ab = k.domain_begin() + k.domain_end();
  std::vector<double> knots(k.knots().rbegin(), k.knots().rend());
  for (double& t : knots) t = ab - t;
  const int nu = surface.num_u(), nv = surface.num_v();
  std::vector<Eigen::Vector4d> cpw(surface.weighted_points().size());
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      cpw[static_cast<size_t>(i * nv + j)] = surface.weighted_point(nu - 1 - i, j);
    }
  }
  return NurbsSurface::FromHomogeneous(KnotVector(k.degree(), std::move(knots)), surface.knots_v(),
                                       std::move(cpw));
}

}  // namespace tangent::nurbs
