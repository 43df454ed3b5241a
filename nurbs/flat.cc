#include "nurbs/flat.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace tangent::nurbs {

namespace {

// The largest distance of points i0 + k·di (k < n) of `s`'s net from the line through the
// first and the last, or +∞ when those coincide (a collapsed edge: a pole).
double OffLine(const NurbsSurface& s, int i0, int j0, int di, int dj, int n) {
  const Eigen::Vector3d a = s.point(i0, j0);
  const Eigen::Vector3d b = s.point(i0 + (n - 1) * di, j0 + (n - 1) * dj);
  const Eigen::Vector3d t = b - a;
  if (!(t.norm() > 0.0)) return INFINITY;
  const Eigen::Vector3d e = t.normalized();
  double worst = 0.0;
  for (int k = 1; k + 1 < n; ++k) {
    const Eigen::Vector3d d = s.point(i0 + k * di, j0 + k * dj) - a;
    worst = std::max(worst, (d - d.dot(e) * e).norm());
  }
  return worst;
}

}  // namespace

std::optional<FlatQuad> FlatQuadOf(const NurbsSurface& s, double tolerance) {
  if (s.periodic_u() || s.periodic_v() || !s.knots_u().IsClamped() || !s.knots_v().IsClamped())
    return std::nullopt;  // (a clamped net's boundary rows are its edges' nets)
  const int nu = s.num_u(), nv = s.num_v();
  // The net's plane: through its centroid, normal to its least principal direction.
  Eigen::Vector3d lo = s.point(0, 0), hi = lo, c = Eigen::Vector3d::Zero();
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const Eigen::Vector3d p = s.point(i, j);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      c += p;
    }
  }
  c /= nu * nv;
  const double size = (hi - lo).norm();
  if (!(size > 0.0)) return std::nullopt;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const Eigen::Vector3d d = s.point(i, j) - c;
      cov += d * d.transpose();
    }
  }
  const Eigen::Vector3d n =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  const double tol = tolerance * size;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      if (std::abs((s.point(i, j) - c).dot(n)) > tol) return std::nullopt;
    }
  }
  // Straight edges: the first and last rows and columns of the net.
  if (OffLine(s, 0, 0, 0, 1, nv) > tol || OffLine(s, nu - 1, 0, 0, 1, nv) > tol ||
      OffLine(s, 0, 0, 1, 0, nu) > tol || OffLine(s, 0, nv - 1, 1, 0, nu) > tol) {
    return std::nullopt;
  }
  const double u0 = s.knots_u().domain_begin(), u1 = s.knots_u().domain_end();
  const double v0 = s.knots_v().domain_begin(), v1 = s.knots_v().domain_end();
  FlatQuad q;
  q.corners = {Eigen::Vector2d(u0, v0), Eigen::Vector2d(u1, v0), Eigen::Vector2d(u1, v1),
               Eigen::Vector2d(u0, v1)};
  q.middle = {0.5 * (u0 + u1), 0.5 * (v0 + v1)};
  for (int k = 0; k < 4; ++k) q.points[k] = s.Evaluate(q.corners[k][0], q.corners[k][1], 0).S;
  return q;
}

}  // namespace tangent::nurbs
