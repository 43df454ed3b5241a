#include "nurbs/knot_vector.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tangent::nurbs {

namespace internal {

void ValidateKnots(int degree, std::span<const double> knots, const std::string& what) {
  auto fail = [&](const std::string& msg) { throw std::invalid_argument(what + ": " + msg); };
  if (degree < 1 || degree > kMaxDegree) {
    fail("unsupported degree " + std::to_string(degree) + " (supported: 1.." +
         std::to_string(kMaxDegree) + ")");
  }
  const size_t p = static_cast<size_t>(degree);
  if (knots.size() < 2 * (p + 1)) {
    fail("has " + std::to_string(knots.size()) + " knots; degree " + std::to_string(degree) +
         " needs at least " + std::to_string(2 * (p + 1)));
  }
  for (size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) fail("knot [" + std::to_string(i) + "] is not finite");
    if (i > 0 && knots[i] < knots[i - 1]) {
      std::ostringstream os;
      os << "knot [" << i << "] = " << knots[i] << " is less than knot [" << i - 1
         << "] = " << knots[i - 1] << " (knots must be non-decreasing)";
      fail(os.str());
    }
  }
  const size_t n = knots.size() - p - 1;
  if (!(knots[p] < knots[n])) fail("empty parametric domain [t_p, t_n]");
  // Interior knots (strictly inside the domain) may repeat at most p times.
  for (size_t i = 0; i < knots.size();) {
    size_t j = i;
    while (j < knots.size() && knots[j] == knots[i]) ++j;
    const size_t mult = j - i;
    const bool interior = knots[i] > knots[p] && knots[i] < knots[n];
    if ((interior && mult > p) || mult > p + 1) {
      std::ostringstream os;
      os << "knot value " << knots[i] << " at [" << i << "] repeats " << mult << " times; at most "
         << (interior ? p : p + 1) << " allowed for degree " << degree;
      fail(os.str());
    }
    i = j;
  }
}

}  // namespace internal

KnotVector::KnotVector(int degree, std::vector<double> knots)
    : degree_(degree), knots_(std::move(knots)) {
  internal::ValidateKnots(degree_, knots_, "knot vector");
}

bool KnotVector::IsClamped() const {
  const int p = degree_;
  for (int i = 1; i <= p; ++i) {
    if ((*this)[i] != (*this)[0] || (*this)[size() - 1 - i] != (*this)[size() - 1]) return false;
  }
  return true;
}

int KnotVector::Multiplicity(double t) const {
  return static_cast<int>(std::count(knots_.begin(), knots_.end(), t));
}

std::vector<double> KnotVector::Breakpoints() const {
  std::vector<double> out;
  for (int i = degree_; i <= num_basis(); ++i) {
    if (out.empty() || (*this)[i] != out.back()) out.push_back((*this)[i]);
  }
  return out;
}

int KnotVector::FindSpan(double t, int hint) const {
  const int p = degree_;
  const int n = num_basis();
  auto in_span = [&](int k) { return k >= p && k < n && (*this)[k] <= t && t < (*this)[k + 1]; };
  if (hint >= p && hint < n) {
    if (in_span(hint)) return hint;
    if (in_span(hint + 1)) return hint + 1;
    if (in_span(hint - 1)) return hint - 1;
  }
  if (t >= domain_end()) {
    int k = n - 1;
    while ((*this)[k] == (*this)[k + 1]) --k;  // Last non-empty span.
    return k;
  }
  if (!(t > domain_begin())) {  // (NaN too)
    int k = p;
    while ((*this)[k] == (*this)[k + 1]) ++k;  // First non-empty span.
    return k;
  }
  // upper_bound gives the first knot > t; the span starts one before it.
  const auto it = std::upper_bound(knots_.begin() + p, knots_.begin() + n + 1, t);
  return static_cast<int>(it - knots_.begin()) - 1;
}

bool KnotVector::IsRefinedBy(const KnotVector& other) const {
  if (other.degree() != degree_) return false;
  if (other.domain_begin() != domain_begin() || other.domain_end() != domain_end()) return false;
  for (int i = degree_ + 1; i < num_basis(); ++i) {
    const double t = (*this)[i];
    if (t <= domain_begin() || t >= domain_end()) continue;
    if (other.Multiplicity(t) < Multiplicity(t)) return false;
  }
  return true;
}

}  // namespace tangent::nurbs
