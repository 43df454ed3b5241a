#pragma once

// The solve on a box that the extremal solvers share (internal header, contact/extremal.cc and
// contact/edge_edge.cc): Newton from the seed, and under Seek::kMinimum, where that does not end
// at a minimum, the bound-constrained minimization, pole escapes and a Newton polish; with the
// tests that classify what it ends at. Templated on the problem size, allocation free.

#include <algorithm>
#include <array>

#include "contact/box_newton.h"
#include "contact/extremal.h"
#include "contact/poles.h"

namespace tangent::contact::internal {

template <int N>
ExtremalStatus StatusOf(const BoxNewtonResult<N>& r) {
  // A singular matrix at the end explains a budget run out (Newton is only linear there), so it
  // takes precedence over "not converged".
  if (r.singular) return ExtremalStatus::kSingular;
  if (!r.converged) return ExtremalStatus::kNotConverged;
  if (std::any_of(r.active.begin(), r.active.end(), [](bool b) { return b; })) {
    return ExtremalStatus::kAtBoundary;
  }
  return ExtremalStatus::kConverged;
}

template <int N>
BoxNewtonOptions<N> BoxOptionsOf(const ExtremalOptions& o) {
  BoxNewtonOptions<N> b;
  b.max_iterations = o.max_iterations;
  b.step_tolerance = o.step_tolerance;
  return b;
}

// The kind of a box extremum: the inertia on the free parameters (Classify); at a vertex of the
// box (nothing free) the held multipliers' signs decide: all of a minimum's, a minimum; all of a
// maximum's, a maximum; mixed, a saddle.
template <int N>
ExtremumKind KindAt(const BoxNewtonResult<N>& r, const NewtonSystem<N>& s,
                    const Eigen::Matrix<double, N, 1>& lo, const Eigen::Matrix<double, N, 1>& hi) {
  if (!std::all_of(r.active.begin(), r.active.end(), [](bool b) { return b; }))
    return Classify<N>(s.hess, r.active, s.classify_scale);
  int as_min = 0;
  for (int i = 0; i < N; ++i) as_min += HoldsAsMinimum<N>(r.x, s.grad, lo, hi, i);
  if (as_min == N) return ExtremumKind::kMinimum;
  if (as_min == 0) return ExtremumKind::kMaximum;
  return ExtremumKind::kSaddle;
}

// A result that is a minimum of ½|d|² on the box: converged, regular, every held parameter's
// multiplier of a minimum's sign, and the Hessian on the free parameters positive (semi)definite.
template <int N>
bool IsBoxMinimum(const BoxNewtonResult<N>& r, const NewtonSystem<N>& s,
                  const Eigen::Matrix<double, N, 1>& lo, const Eigen::Matrix<double, N, 1>& hi) {
  if (!r.converged || r.singular) return false;
  for (int i = 0; i < N; ++i) {
    if (r.active[static_cast<size_t>(i)] && !HoldsAsMinimum<N>(r.x, s.grad, lo, hi, i))
      return false;
  }
  return KindAt<N>(r, s, lo, hi) == ExtremumKind::kMinimum;
}

// A regular interior extremum of an interpenetrating pair: the penetration extremum.
template <int N>
bool IsPenetration(const BoxNewtonResult<N>& r, const NewtonSystem<N>& s) {
  return r.converged && !r.singular && s.penetrating &&
         std::none_of(r.active.begin(), r.active.end(), [](bool b) { return b; });
}

// What Seek::kMinimum accepts: a box minimum, or the penetration extremum.
template <int N>
bool Acceptable(const BoxNewtonResult<N>& r, const NewtonSystem<N>& s,
                const Eigen::Matrix<double, N, 1>& lo, const Eigen::Matrix<double, N, 1>& hi) {
  return IsBoxMinimum<N>(r, s, lo, hi) || IsPenetration<N>(r, s);
}

// Newton from the seed; under Seek::kMinimum, when that does not end at an acceptable extremum,
// the bound-constrained minimization from the same seed (restarted off a pole it stops on) and a
// Newton polish on its active face (release by the multipliers' sign). `eval` must leave the
// problem's own evaluation state at the last point it was called with: on return that is the
// returned r.x. `pole(x, &y)` looks for a pole at or next to x: kEscape with y a seed just off
// it along the best departure, kExtremum with y the pole pair (the other parameters solved for
// the pole point) when the pole itself is the minimum, kNone otherwise.
template <int N, class Eval, class Pole>
BoxNewtonResult<N> SolveOnBox(Eval&& eval, Pole&& pole, const Eigen::Matrix<double, N, 1>& seed,
                              const Eigen::Matrix<double, N, 1>& lo,
                              const Eigen::Matrix<double, N, 1>& hi, const BoxNewtonOptions<N>& opt,
                              Seek seek, NewtonSystem<N>* at_x) {
  using Vec = Eigen::Matrix<double, N, 1>;
  NewtonSystem<N> last;
  double seed_value = -1.0;  // ½|d|² at the (clamped) seed: BoxNewton's first evaluation
  auto recorded = [&](const Vec& x, NewtonSystem<N>* s) {
    eval(x, s);
    last = *s;
    if (seed_value < 0.0) seed_value = s->value;
  };
  BoxNewtonResult<N> first = BoxNewton<N>(recorded, seed, lo, hi, opt);
  int iterations = first.iterations;
  // The pole pair as the answer: converged, nothing held (a pole is not an edge).
  auto at_pole = [&](const Vec& y) {
    BoxNewtonResult<N> r;
    r.x = y;
    r.converged = true;
    r.iterations = iterations;
    r.rcond = 0.0;
    eval(y, at_x);
    return r;
  };
  Vec y;
  // A touching pair (NewtonSystem::touching) is the minimum; on a pole row, the pole pair.
  auto touching = [&](BoxNewtonResult<N> r) {
    if (pole(r.x, &y) == PoleAction::kExtremum) return at_pole(y);
    r.iterations = iterations;
    *at_x = last;
    return r;
  };
  // A minimum farther apart than the seed's own pair lies in another basin: Newton on F is not
  // a descent method and can cross to it. (A penetration extremum may be deeper than the seed.)
  const bool uphill = last.value > seed_value * (1.0 + 1e-12) + 1e-300;
  if (first.converged && last.touching) return touching(first);
  if (seek == Seek::kNearest || (IsBoxMinimum<N>(first, last, lo, hi) && !uphill) ||
      IsPenetration<N>(first, last)) {
    *at_x = last;
    return first;
  }
  BoxNewtonResult<N> m = BoxMinimize<N>(recorded, seed, lo, hi, opt);
  iterations += m.iterations;
  if (m.converged && last.touching) return touching(m);
  for (int escapes = 0; escapes < 3; ++escapes) {
    const PoleAction action = pole(m.x, &y);
    if (action == PoleAction::kExtremum) return at_pole(y);
    if (action == PoleAction::kNone) break;
    m = BoxMinimize<N>(recorded, y, lo, hi, opt);
    iterations += m.iterations;
  }
  BoxNewtonOptions<N> polish = opt;
  polish.initial_active = m.active;
  polish.release_by_gradient = true;
  BoxNewtonResult<N> second = BoxNewton<N>(recorded, m.x, lo, hi, polish);
  iterations += second.iterations;
  if (Acceptable<N>(second, last, lo, hi)) {
    second.iterations = iterations;
    *at_x = last;
    return second;
  }
  // Newton near a pole slows to linear and stops singular: the pole itself may be the answer.
  for (const Vec* x : {&second.x, &m.x}) {
    if (pole(*x, &y) == PoleAction::kExtremum) return at_pole(y);
  }
  // Neither is a minimum: keep Newton's answer and its honest flags.
  NewtonSystem<N> again;
  eval(first.x, &again);
  *at_x = again;
  first.iterations = iterations;
  return first;
}

}  // namespace tangent::contact::internal
