// The clearance guard (clearance_guard.h): the motion bound and the step's fraction.

#include "optimizer/clearance_guard.h"

#include <algorithm>
#include <cmath>

namespace tangent::optimizer {

namespace {

// The end of the admissible fractions [0, α*] ⊂ [0, hi] of a step whose motion only grows with
// α (the segment only lengthens), by bisection to 2⁻²⁰ of hi: the largest α found admissible.
template <class Admissible>
double LargestFraction(double hi, Admissible&& admissible) {
  double lo = 0.0;
  for (int i = 0; i < 20; ++i) {
    const double mid = 0.5 * (lo + hi);
    (admissible(mid) ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

void ClearanceGuard::Configure(const Mechanism& mechanism, std::vector<std::pair<int, int>> pairs,
                               std::vector<double> reach) {
  mechanism_ = &mechanism;
  pairs_ = std::move(pairs);
  reach_ = std::move(reach);
  reach_.resize(static_cast<size_t>(mechanism.num_bodies()), 0.0);
  bounded_.assign(reach_.size(), 0);
  return_bounded_.assign(reach_.size(), 0);
  q_ref_ = mechanism.InitialCoordinates();
  candidate_ref_ = q_ref_;
  clearance_.assign(pairs_.size(), kInfinity);
  candidate_ = clearance_;
  armed_ = false;
}

double ClearanceGuard::Motion(int b, const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q,
                              const Eigen::VectorXd& step, double alpha) const {
  const int o = mechanism_->offset(b);
  if (o < 0) return 0.0;
  const Eigen::Vector3d t_ref = q_ref.segment<3>(o);
  const Eigen::Vector3d t0 = q.segment<3>(o);
  const Eigen::Vector3d t1 = t0 + alpha * step.segment<3>(o);
  const double translation = std::max((t0 - t_ref).norm(), (t1 - t_ref).norm());
  const double reach = reach_[static_cast<size_t>(b)];
  if (reach == 0.0) return translation;
  // cos and sin of half the rotation angles: cos(θ/2) = |⟨Q, Q'⟩| / (|Q| |Q'|) from the raw
  // coordinates (either sign of a quaternion is the same rotation), one square root a pair.
  const auto Q_ref = q_ref.segment<4>(o + 3);
  const auto Q0 = q.segment<4>(o + 3);
  const Eigen::Vector4d Q1 = Q0 + alpha * step.segment<4>(o + 3);
  const double n0 = Q0.squaredNorm();
  const double ca = std::min(1.0, std::abs(Q_ref.dot(Q0)) / std::sqrt(Q_ref.squaredNorm() * n0));
  const double cb = std::min(1.0, std::abs(Q0.dot(Q1)) / std::sqrt(n0 * Q1.squaredNorm()));
  const double sa = std::sqrt(1.0 - ca * ca), sb = std::sqrt(1.0 - cb * cb);
  // sin((a + b)/2) while (a + b)/2 < π/2; beyond, the chord's largest value 2.
  const double chord = ca * cb - sa * sb <= 0.0 ? 2.0 : 2.0 * (sa * cb + ca * sb);
  return translation + chord * reach;
}

double ClearanceGuard::MotionFraction(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q,
                                      const Eigen::VectorXd& step, double alpha,
                                      double bound) const {
  // Each marked body's admissible fractions are an interval [0, α_b]; the step's is the least.
  for (size_t k = 0; k < reach_.size(); ++k) {
    const int b = static_cast<int>(k);
    if (!bounded_[k] || Motion(b, q_ref, q, step, alpha) <= bound) continue;
    alpha = LargestFraction(alpha, [&](double a) { return Motion(b, q_ref, q, step, a) <= bound; });
  }
  return alpha;
}

bool ClearanceGuard::ReturnWithin(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& q,
                                  double bound) const {
  for (size_t k = 0; k < reach_.size(); ++k) {
    // (A zero fraction of any step is the point q itself: q stands in for the step.)
    if (return_bounded_[k] && !(Motion(static_cast<int>(k), q_ref, q, q, 0.0) <= bound)) {
      return false;
    }
  }
  return true;
}

bool ClearanceGuard::Within(const Eigen::VectorXd& q_ref, const std::vector<double>& clearance,
                            const Eigen::VectorXd& q, const Eigen::VectorXd& step,
                            double alpha) const {
  for (size_t k = 0; k < pairs_.size(); ++k) {
    const double c = clearance[k];
    if (!(c < kInfinity)) continue;
    const double mu = Motion(pairs_[k].first, q_ref, q, step, alpha) +
                      Motion(pairs_[k].second, q_ref, q, step, alpha);
    if (!(mu <= kShare * c)) return false;
  }
  return true;
}

double ClearanceGuard::Fraction(const Eigen::VectorXd& q, const Eigen::VectorXd& step) const {
  if (!armed_ || Within(q_ref_, clearance_, q, step, 1.0)) return 1.0;
  return LargestFraction(1.0, [&](double a) { return Within(q_ref_, clearance_, q, step, a); });
}

}  // namespace tangent::optimizer
