#include "nurbs/curve.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "nurbs/basis.h"
#include "nurbs/bezier_nets.h"

namespace tangent::nurbs {

template <int Dim>
NurbsCurve<Dim>::NurbsCurve(KnotVector knots, const std::vector<Vec>& points,
                            const std::vector<double>& weights)
    : knots_(std::move(knots)) {
  const size_t n = static_cast<size_t>(num_points());
  if (points.size() != n) {
    std::ostringstream os;
    os << "NURBS curve: " << points.size() << " control points given; " << knots_.size()
       << " knots of degree " << degree() << " need " << n;
    throw std::invalid_argument(os.str());
  }
  if (!weights.empty() && weights.size() != n) {
    throw std::invalid_argument("NURBS curve: " + std::to_string(weights.size()) +
                                " weights given for " + std::to_string(n) + " control points");
  }
  cpw_.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    if (!points[k].allFinite()) {
      throw std::invalid_argument("NURBS curve: control point [" + std::to_string(k) +
                                  "] has a non-finite coordinate");
    }
    if (!std::isfinite(w) || !(w > 0.0)) {
      std::ostringstream os;
      os << "NURBS curve: weight [" << k << "] = " << w << " must be positive and finite";
      throw std::invalid_argument(os.str());
    }
    if (!(w >= kMinWeight && w <= kMaxWeight) ||
        !(points[k].cwiseAbs().maxCoeff() * std::max(w, 1.0) <= kMaxCoordinate)) {
      std::ostringstream os;
      os << "NURBS curve: control point [" << k << "] with weight " << w
         << " is out of range: weights must lie in [1e-100, 1e100] and coordinates, also "
            "times their weight, within 1e100 (evaluation would overflow)";
      throw std::invalid_argument(os.str());
    }
    cpw_[k] << w * points[k], w;
  }
  Finish();
}

template <int Dim>
NurbsCurve<Dim>::NurbsCurve(KnotVector knots, std::vector<HPoint> cpw, int)
    : knots_(std::move(knots)), cpw_(std::move(cpw)) {}

template <int Dim>
NurbsCurve<Dim> NurbsCurve<Dim>::FromHomogeneous(KnotVector knots,
                                                 std::vector<HPoint> weighted_points) {
  if (weighted_points.size() != static_cast<size_t>(knots.num_basis())) {
    throw std::invalid_argument("NURBS curve: " + std::to_string(weighted_points.size()) +
                                " homogeneous control points given, knot vector needs " +
                                std::to_string(knots.num_basis()));
  }
  for (size_t k = 0; k < weighted_points.size(); ++k) {
    if (!weighted_points[k].allFinite() || !(weighted_points[k][Dim] > 0.0)) {
      throw std::invalid_argument("NURBS curve: homogeneous control point " + std::to_string(k) +
                                  " is not finite or has a non-positive weight");
    }
    const double w = weighted_points[k][Dim];
    if (!(w >= kMinWeight && w <= kMaxWeight) ||
        !(weighted_points[k].template head<Dim>().cwiseAbs().maxCoeff() <=
          kMaxCoordinate * std::min(w, 1.0))) {
      throw std::invalid_argument("NURBS curve: homogeneous control point " + std::to_string(k) +
                                  " is out of range: weights must lie in [1e-100, 1e100] and "
                                  "coordinates, also times their weight, within 1e100");
    }
  }
  NurbsCurve c(std::move(knots), std::move(weighted_points), 0);
  c.Finish();
  return c;
}

template <int Dim>
void NurbsCurve<Dim>::Finish() {
  fast_ = internal::BuildSpanForm<Dim>(knots_, cpw_);
}

template <int Dim>
CurvePoint<Dim> EvaluateReference(const NurbsCurve<Dim>& curve, double t, int order) {
  const KnotVector& k = curve.knots();
  t = k.Clamp(t);
  order = std::clamp(order, 0, kMaxOrder);
  const int p = k.degree();
  const int span = k.FindSpan(t);
  BasisTable n{};
  BasisDerivatives(k, span, t, order, &n);
  HomogeneousCurveDerivs<Dim> h;
  for (int d = 0; d <= order; ++d) {
    h.A[d].setZero();
    for (int i = 0; i <= p; ++i) {
      h.A[d] += n[static_cast<size_t>(d)][static_cast<size_t>(i)] *
                curve.weighted_points()[static_cast<size_t>(span - p + i)];
    }
  }
  CurvePoint<Dim> out;
  RationalQuotient(h, order, &out);
  return out;
}

template class NurbsCurve<2>;
template class NurbsCurve<3>;
template CurvePoint<2> EvaluateReference(const NurbsCurve<2>&, double, int);
template CurvePoint<3> EvaluateReference(const NurbsCurve<3>&, double, int);

}  // namespace tangent::nurbs
