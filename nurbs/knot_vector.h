#pragma once

#include <span>
#include <string>
#include <vector>

namespace tangent::nurbs {

/// Highest polynomial degree supported in either parameter direction.
inline constexpr int kMaxDegree = 9;

/// A validated knot vector of a B-spline of degree `p` with `n` control points:
/// `n + p + 1` non-decreasing, finite knots. The parametric domain is `[t_p, t_n]`.
/// Interior knots may repeat up to `p` times (the spline stays C⁰); the first and last
/// `p + 1` knots may be clamped (repeated) or not.
class KnotVector {
 public:
  /// @throws std::invalid_argument naming the offending knot or count when the knots are
  ///   not finite, decrease, repeat more than allowed, or leave an empty domain.
  KnotVector(int degree, std::vector<double> knots);

  int degree() const { return degree_; }
  /// Number of control points (basis functions) this knot vector supports.
  int num_basis() const { return static_cast<int>(knots_.size()) - degree_ - 1; }
  const std::vector<double>& knots() const { return knots_; }
  double operator[](int i) const { return knots_[static_cast<size_t>(i)]; }
  int size() const { return static_cast<int>(knots_.size()); }
  double domain_begin() const { return knots_[static_cast<size_t>(degree_)]; }
  double domain_end() const { return knots_[static_cast<size_t>(num_basis())]; }

  /// True when the first and last `p + 1` knots are equal (curve interpolates end points).
  bool IsClamped() const;
  /// Number of knots equal to `t` (exact comparison).
  int Multiplicity(double t) const;
  /// Distinct knot values inside the domain, in increasing order (the span breakpoints).
  std::vector<double> Breakpoints() const;

  /// Index k with `t_k <= t < t_{k+1}` and `p <= k < n`; `t` is clamped to the domain and the
  /// domain end belongs to the last non-empty span; a NaN `t` gives the first non-empty span
  /// (never an index outside [p, n)). `hint` (a previous answer) is tried first together with
  /// its neighbours, so coherent queries cost O(1); any value is accepted.
  int FindSpan(double t, int hint = -1) const;
  /// t clamped to the domain; NaN gives the domain's start (every evaluation path calls this,
  /// so a non-finite parameter evaluates a defined point and never reads outside the net).
  double Clamp(double t) const {
    return t >= domain_begin() ? (t <= domain_end() ? t : domain_end()) : domain_begin();
  }

  /// Whether `other` contains every knot of this vector's domain with at least the same
  /// multiplicity and has the same domain (the condition for refinement).
  bool IsRefinedBy(const KnotVector& other) const;

 private:
  int degree_;
  std::vector<double> knots_;
};

namespace internal {
/// Shared validation; `what` names the knot vector in messages (e.g. "knots_u").
void ValidateKnots(int degree, std::span<const double> knots, const std::string& what);
}  // namespace internal

}  // namespace tangent::nurbs
