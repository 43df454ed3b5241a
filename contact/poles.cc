#include "contact/poles.h"

#include <cmath>
#include <limits>

namespace tangent::contact::internal {

namespace {

// Number of departure angles sampled around a pole (the best is then refined by the solve).
constexpr int kPoleAngles = 64;

}  // namespace

PoleRow FindPoleRow(const nurbs::NurbsSurface& s, const Eigen::Vector2d& uv, double fraction) {
  for (int across : {1, 0}) {
    if (across == 1 ? s.periodic_v() : s.periodic_u()) continue;  // no edge to collapse
    const nurbs::KnotVector& k = across == 1 ? s.knots_v() : s.knots_u();
    const double lo = k.domain_begin(), hi = k.domain_end(), w = hi - lo;
    PoleRow row;
    row.found = true;
    row.across = across;
    if (uv[across] - lo <= fraction * w) {
      row.bound = lo;
      row.inward = 1.0;
    } else if (hi - uv[across] <= fraction * w) {
      row.bound = hi;
      row.inward = -1.0;
    } else {
      continue;
    }
    if (IsPoleRowAt(s, across, row.bound, uv)) return row;
  }
  return {};
}

bool IsPoleRowAt(const nurbs::NurbsSurface& s, int across, double bound,
                 const Eigen::Vector2d& uv) {
  Eigen::Vector2d at = uv;
  at[across] = bound;
  const nurbs::SurfacePoint p = s.Evaluate(at[0], at[1], 1);
  const Eigen::Vector3d& along = across == 1 ? p.S_u : p.S_v;
  const Eigen::Vector3d& off = across == 1 ? p.S_v : p.S_u;
  return off.norm() > 0.0 && along.norm() <= nurbs::kDegenerateRatio * off.norm();
}

Eigen::Vector2d OffPole(const nurbs::NurbsSurface& s, const PoleRow& row, double angle) {
  const nurbs::KnotVector& k = row.across == 1 ? s.knots_v() : s.knots_u();
  Eigen::Vector2d uv;
  uv[1 - row.across] = angle;
  uv[row.across] = row.bound + row.inward * 1e-3 * (k.domain_end() - k.domain_begin());
  return uv;
}

double BestDeparture(const nurbs::NurbsSurface& s, const BodyPose& pose, const PoleRow& row,
                     const Eigen::Vector3d& d, double sign, double* angle) {
  const nurbs::KnotVector& k = row.across == 1 ? s.knots_u() : s.knots_v();
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kPoleAngles; ++i) {
    const double a = k.domain_begin() +
                     (k.domain_end() - k.domain_begin()) * i / static_cast<double>(kPoleAngles);
    const nurbs::SurfacePoint p =
        row.across == 1 ? s.Evaluate(a, row.bound, 1) : s.Evaluate(row.bound, a, 1);
    const Eigen::Vector3d t = pose.R_WB * (row.across == 1 ? p.S_v : p.S_u) * row.inward;
    const double slope = sign * d.dot(t) / t.norm();
    if (slope < best) {
      best = slope;
      *angle = a;
    }
  }
  return best;
}

// ½|d|² with the other point fixed must not decrease at small departures in any direction.
bool PoleIsMinimum(const nurbs::NurbsSurface& s, const BodyPose& pose, const PoleRow& row,
                   const Eigen::Vector3d& other, double* descent_angle) {
  const nurbs::KnotVector& ka = row.across == 1 ? s.knots_u() : s.knots_v();
  const nurbs::KnotVector& kx = row.across == 1 ? s.knots_v() : s.knots_u();
  const Eigen::Vector3d pole =
      pose.Point(row.across == 1 ? s.Evaluate(ka.domain_begin(), row.bound, 0).S
                                 : s.Evaluate(row.bound, ka.domain_begin(), 0).S);
  const double at_pole = (pole - other).squaredNorm();
  const double off = row.bound + row.inward * 1e-4 * (kx.domain_end() - kx.domain_begin());
  double lowest = at_pole * (1.0 - 1e-12);
  bool minimum = true;
  for (int i = 0; i < 16; ++i) {
    const double a = ka.domain_begin() + (ka.domain_end() - ka.domain_begin()) * i / 16.0;
    const Eigen::Vector3d p =
        pose.Point(row.across == 1 ? s.Evaluate(a, off, 0).S : s.Evaluate(off, a, 0).S);
    const double d = (p - other).squaredNorm();
    if (d < lowest) {
      lowest = d;
      minimum = false;
      if (descent_angle) *descent_angle = a;
    }
  }
  return minimum;
}

bool IsVertex(const nurbs::NurbsSurface& s, const PoleRow& row) {
  const nurbs::KnotVector& ka = row.across == 1 ? s.knots_u() : s.knots_v();
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    const double a = ka.domain_begin() + (ka.domain_end() - ka.domain_begin()) * (i + 0.25) / 3.0;
    const double u = row.across == 1 ? a : row.bound, v = row.across == 1 ? row.bound : a;
    const Eigen::Vector3d n = nurbs::UnitNormal(s, u, v, s.Evaluate(u, v, 2));
    if (i == 0) {
      first = n;
    } else if ((n - first).norm() > 1e-6) {
      return true;
    }
  }
  return false;
}

}  // namespace tangent::contact::internal
