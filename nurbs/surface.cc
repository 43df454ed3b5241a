#include "nurbs/surface.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "nurbs/basis.h"
#include "nurbs/bezier_nets.h"

namespace tangent::nurbs {

namespace {

std::string Index2(int i, int j) {
  return "[" + std::to_string(i) + "][" + std::to_string(j) + "]";
}

}  // namespace

NurbsSurface::NurbsSurface(KnotVector knots_u, KnotVector knots_v,
                           const std::vector<Eigen::Vector3d>& points,
                           const std::vector<double>& weights)
    : knots_u_(std::move(knots_u)), knots_v_(std::move(knots_v)) {
  const size_t n = static_cast<size_t>(num_u()) * static_cast<size_t>(num_v());
  if (points.size() != n) {
    std::ostringstream os;
    os << "NURBS surface: " << points.size() << " control points given; knot vectors of "
       << knots_u_.size() << " (degree " << degree_u() << ") and " << knots_v_.size() << " (degree "
       << degree_v() << ") knots need " << num_u() << " x " << num_v() << " = " << n;
    throw std::invalid_argument(os.str());
  }
  if (!weights.empty() && weights.size() != n) {
    throw std::invalid_argument("NURBS surface: " + std::to_string(weights.size()) +
                                " weights given for " + std::to_string(n) + " control points");
  }
  cpw_.resize(n);
  for (int i = 0; i < num_u(); ++i) {
    for (int j = 0; j < num_v(); ++j) {
      const size_t k = static_cast<size_t>(i * num_v() + j);
      const double w = weights.empty() ? 1.0 : weights[k];
      if (!points[k].allFinite()) {
        throw std::invalid_argument("NURBS surface: control point " + Index2(i, j) +
                                    " has a non-finite coordinate");
      }
      if (!std::isfinite(w) || !(w > 0.0)) {
        std::ostringstream os;
        os << "NURBS surface: weight " << Index2(i, j) << " = " << w
           << " must be positive and finite";
        throw std::invalid_argument(os.str());
      }
      if (!(w >= kMinWeight && w <= kMaxWeight) ||
          !(points[k].cwiseAbs().maxCoeff() * std::max(w, 1.0) <= kMaxCoordinate)) {
        std::ostringstream os;
        os << "NURBS surface: control point " << Index2(i, j) << " (" << points[k].transpose()
           << ") with weight " << w << " is out of range: weights must lie in [1e-100, 1e100] "
           << "and coordinates, also times their weight, within 1e100 (evaluation would "
              "overflow)";
        throw std::invalid_argument(os.str());
      }
      cpw_[k] << w * points[k], w;
    }
  }
  Finish();
}

NurbsSurface::NurbsSurface(KnotVector knots_u, KnotVector knots_v, std::vector<Eigen::Vector4d> cpw,
                           int)
    : knots_u_(std::move(knots_u)), knots_v_(std::move(knots_v)), cpw_(std::move(cpw)) {}

NurbsSurface NurbsSurface::FromHomogeneous(KnotVector knots_u, KnotVector knots_v,
                                           std::vector<Eigen::Vector4d> weighted_points) {
  const size_t n =
      static_cast<size_t>(knots_u.num_basis()) * static_cast<size_t>(knots_v.num_basis());
  if (weighted_points.size() != n) {
    throw std::invalid_argument("NURBS surface: " + std::to_string(weighted_points.size()) +
                                " homogeneous control points given, knot vectors need " +
                                std::to_string(n));
  }
  for (size_t k = 0; k < n; ++k) {
    if (!weighted_points[k].allFinite() || !(weighted_points[k][3] > 0.0)) {
      throw std::invalid_argument("NURBS surface: homogeneous control point " + std::to_string(k) +
                                  " is not finite or has a non-positive weight");
    }
    const double w = weighted_points[k][3];
    if (!(w >= kMinWeight && w <= kMaxWeight) ||
        !(weighted_points[k].head<3>().cwiseAbs().maxCoeff() <=
          kMaxCoordinate * std::min(w, 1.0))) {
      throw std::invalid_argument("NURBS surface: homogeneous control point " + std::to_string(k) +
                                  " is out of range: weights must lie in [1e-100, 1e100] and "
                                  "coordinates, also times their weight, within 1e100");
    }
  }
  NurbsSurface s(std::move(knots_u), std::move(knots_v), std::move(weighted_points), 0);
  s.Finish();
  return s;
}

void NurbsSurface::Finish() {
  rational_ = std::any_of(cpw_.begin(), cpw_.end(),
                          [&](const Eigen::Vector4d& h) { return h[3] != cpw_.front()[3]; });
  // A polynomial surface (all weights equal) is stored divided by its weight, so the fast path
  // reads S directly and skips the quotient rule.
  fast_ =
      internal::BuildSpanForm(knots_u_, knots_v_, cpw_, rational_ ? 1.0 : 1.0 / cpw_.front()[3]);
  // Seams: compare both ends at 9 stations across (position to 1e-12 of the net's size, first
  // derivative to 1e-9 relative).
  double size = 0.0;
  for (const Eigen::Vector4d& h : cpw_) size = std::max(size, (h.head<3>() / h[3]).norm());
  auto seam = [&](bool along_u) {
    const KnotVector& k = along_u ? knots_u_ : knots_v_;
    const KnotVector& o = along_u ? knots_v_ : knots_u_;
    for (int i = 0; i <= 8; ++i) {
      const double t = o.domain_begin() + (o.domain_end() - o.domain_begin()) * i / 8.0;
      const SurfacePoint a =
          along_u ? Evaluate(k.domain_begin(), t, 1) : Evaluate(t, k.domain_begin(), 1);
      const SurfacePoint b =
          along_u ? Evaluate(k.domain_end(), t, 1) : Evaluate(t, k.domain_end(), 1);
      const Eigen::Vector3d da = along_u ? a.S_u : a.S_v, db = along_u ? b.S_u : b.S_v;
      if ((a.S - b.S).norm() > 1e-12 * (1.0 + size)) return false;
      if ((da - db).norm() > 1e-9 * (da.norm() + db.norm()) + 1e-14 * (1.0 + size)) return false;
    }
    return true;
  };
  periodic_u_ = seam(true);
  periodic_v_ = seam(false);
}

SurfacePoint NurbsSurface::Evaluate(double u, double v, int order) const {
  SpanHint hint;
  SurfacePoint out;
  switch (order) {
    case 0:
      Evaluate<0>(u, v, &hint, &out);
      break;
    case 1:
      Evaluate<1>(u, v, &hint, &out);
      break;
    default:
      Evaluate<2>(u, v, &hint, &out);
      break;
  }
  return out;
}

SurfacePoint EvaluateReference(const NurbsSurface& surface, double u, double v, int order) {
  const KnotVector& ku = surface.knots_u();
  const KnotVector& kv = surface.knots_v();
  u = ku.Clamp(u);
  v = kv.Clamp(v);
  order = std::clamp(order, 0, kMaxOrder);
  const int p = ku.degree();
  const int q = kv.degree();
  const int su = ku.FindSpan(u);
  const int sv = kv.FindSpan(v);
  BasisTable nu{}, nv{};
  BasisDerivatives(ku, su, u, order, &nu);
  BasisDerivatives(kv, sv, v, order, &nv);
  // A^(k,l) = Σ_i Σ_j N_i^(k)(u) M_j^(l)(v) P^w_ij for k + l ≤ order.
  HomogeneousSurfaceDerivs h;
  const int kl[6][2] = {{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
  const int count = order == 0 ? 1 : (order == 1 ? 3 : 6);
  for (int d = 0; d < count; ++d) {
    Eigen::Vector4d acc = Eigen::Vector4d::Zero();
    for (int i = 0; i <= p; ++i) {
      Eigen::Vector4d row = Eigen::Vector4d::Zero();
      for (int j = 0; j <= q; ++j) {
        row += nv[static_cast<size_t>(kl[d][1])][static_cast<size_t>(j)] *
               surface.weighted_point(su - p + i, sv - q + j);
      }
      acc += nu[static_cast<size_t>(kl[d][0])][static_cast<size_t>(i)] * row;
    }
    h.A[d] = acc;
  }
  SurfacePoint out;
  RationalQuotient(h, order, &out);
  return out;
}

bool IsDegenerate(const SurfacePoint& p) {
  constexpr double r2 = kDegenerateRatio * kDegenerateRatio;
  const double a2 = p.S_u.squaredNorm(), b2 = p.S_v.squaredNorm();
  return !(a2 > r2 * b2) || !(b2 > r2 * a2);
}

Eigen::Vector3d UnitNormal(const NurbsSurface& surface, double u, double v, const SurfacePoint& p) {
  if (!IsDegenerate(p)) return p.S_u.cross(p.S_v).normalized();
  const KnotVector& ku = surface.knots_u();
  const KnotVector& kv = surface.knots_v();
  // The inward sign along each direction: + in the lower half of the domain, − in the upper.
  const double su = u < 0.5 * (ku.domain_begin() + ku.domain_end()) ? 1.0 : -1.0;
  const double sv = v < 0.5 * (kv.domain_begin() + kv.domain_end()) ? 1.0 : -1.0;
  const double a = p.S_u.norm(), b = p.S_v.norm();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  if (b > kDegenerateRatio * a) {
    n = sv * p.S_uv.cross(p.S_v);  // S_u vanished
  } else if (a > kDegenerateRatio * b) {
    n = su * p.S_u.cross(p.S_uv);  // S_v vanished
  }
  const double scale = std::max(p.S_uv.squaredNorm(), std::max(a * a, b * b));
  if (n.norm() > 1e-10 * scale) return n.normalized();
  SpanHint hint;
  SurfacePoint q;
  surface.Evaluate<1>(u + su * 1e-7 * (ku.domain_end() - ku.domain_begin()),
                      v + sv * 1e-7 * (kv.domain_end() - kv.domain_begin()), &hint, &q);
  return q.S_u.cross(q.S_v).normalized();
}

}  // namespace tangent::nurbs
