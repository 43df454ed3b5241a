#pragma once

// What the extremal solvers share about their inputs (internal header, contact/extremal.cc and
// contact/point_curve_extremal.cc): domains, the first fundamental form's scale, and the defined
// answer to a non-finite seed or pose.

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>

#include "contact/extremal.h"

namespace tangent::contact::internal {

inline double FirstFormScale(const nurbs::SurfacePoint& p) {
  return std::max(p.S_u.squaredNorm(), p.S_v.squaredNorm());
}

inline Eigen::Vector2d Lo(const nurbs::NurbsSurface& s) {
  return {s.knots_u().domain_begin(), s.knots_v().domain_begin()};
}
inline Eigen::Vector2d Hi(const nurbs::NurbsSurface& s) {
  return {s.knots_u().domain_end(), s.knots_v().domain_end()};
}

/// A surface pair's parameter box (u, v, s, t): bounds and which directions wrap round.
struct PairBox {
  Eigen::Vector4d lo, hi;
  std::array<bool, 4> periodic;
};
inline PairBox PairBoxOf(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g) {
  PairBox b;
  b.lo << Lo(f), Lo(g);
  b.hi << Hi(f), Hi(g);
  b.periodic = {f.periodic_u(), f.periodic_v(), g.periodic_u(), g.periodic_v()};
  return b;
}

inline bool FinitePose(const BodyPose& p) { return p.q.allFinite() && p.R_WB.allFinite(); }

// The seed with each non-finite component replaced by the middle of its domain.
template <int N>
Eigen::Matrix<double, N, 1> SaneSeed(const Eigen::Matrix<double, N, 1>& seed,
                                     const Eigen::Matrix<double, N, 1>& lo,
                                     const Eigen::Matrix<double, N, 1>& hi) {
  Eigen::Matrix<double, N, 1> x = seed;
  for (int i = 0; i < N; ++i) {
    if (!std::isfinite(x[i])) x[i] = 0.5 * (lo[i] + hi[i]);
  }
  return x;
}

// The defined answer to a non-finite seed or pose (ExtremalStatus::kInvalidInput).
template <class Extremum, int N>
Extremum InvalidExtremum(const Eigen::Matrix<double, N, 1>& u) {
  Extremum out;
  out.u = u;
  out.status = ExtremalStatus::kInvalidInput;
  out.kind = ExtremumKind::kDegenerate;
  out.p_f.setZero();
  out.R_WCf.setIdentity();
  return out;
}

}  // namespace tangent::contact::internal
