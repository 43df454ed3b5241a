#pragma once

// Damped Newton on a box (the parameter domains), shared by the extremal-distance solvers.
// Internal header: templated on the problem size N (2, 3, 4), fixed-size Eigen only, so a call
// allocates nothing.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

namespace tangent::contact::internal {

/// What a problem provides at x: the interior system (equations regular at contact) and the
/// gradient / Hessian of ½|d|², used when some parameters sit on the domain boundary.
template <int N>
struct NewtonSystem {
  Eigen::Matrix<double, N, 1> F;
  Eigen::Matrix<double, N, N> J;
  Eigen::Matrix<double, N, 1> grad;
  Eigen::Matrix<double, N, N> hess;
  /// Natural size of the Newton matrix's entries (e.g. |S_u|² for a point problem), or 0. A
  /// matrix whose entries are all below kSingularRcond · scale is singular even when it is
  /// well conditioned relative to itself (a focal point shrinks a Hessian isotropically).
  double scale = 0.0;
};

/// Reciprocal condition below which a Newton or Jacobian matrix counts as singular: u_q solved
/// from it would carry a relative error of ~eps/rcond ≈ 1e-6, the accuracy the optimizer's
/// constraint Jacobians are held to, and Newton's convergence is no longer quadratic.
inline constexpr double kSingularRcond = 1e-10;

/// Whether a square matrix is singular by that measure, from its full-pivot LU: the ratio of the
/// last pivot to the first estimates the reciprocal condition (cheaply, unlike Eigen's rcond(),
/// which runs an iterative estimate and, on the invertible part only, returns 1 for a
/// rank-deficient matrix). With full pivoting the first pivot is also the largest entry, which
/// `scale` (the natural size of the entries, or 0) is checked against.
template <int N>
bool IsSingular(const Eigen::FullPivLU<Eigen::Matrix<double, N, N>>& lu, double scale,
                double* rcond) {
  const double first = std::abs(lu.matrixLU()(0, 0));
  const double last = std::abs(lu.matrixLU()(N - 1, N - 1));
  *rcond = first > 0.0 ? last / first : 0.0;
  // "Negligible against the natural scale" is 1e-6 of it (kSingularRcond · 1e4): near a focal
  // point the iterate stops ~1e-8 away in parameters and the matrix is that small (docs/
  // stability.md), while regular extrema keep entries of the scale's order.
  return !(*rcond > kSingularRcond) || !std::isfinite(*rcond) ||
         (scale > 0.0 && !(first > kSingularRcond * 1e4 * scale));
}

/// Full-pivot LU of a small matrix.
template <int N>
Eigen::FullPivLU<Eigen::Matrix<double, N, N>> Factor(const Eigen::Matrix<double, N, N>& a) {
  return Eigen::FullPivLU<Eigen::Matrix<double, N, N>>(a);
}

template <int N>
struct BoxNewtonResult {
  Eigen::Matrix<double, N, 1> x;
  std::array<bool, N> active{};  ///< parameter held on the domain boundary
  int iterations = 0;
  bool converged = false;
  bool singular = false;  ///< the final Newton matrix was (numerically) singular
  double rcond = 0.0;     ///< reciprocal condition estimate of the final Newton matrix
};

template <int N>
struct BoxNewtonOptions {
  int max_iterations = 40;
  double step_tolerance = 1e-13;  ///< on each step component divided by its domain width
  /// Parameters of closed (periodic) directions: they wrap around the domain instead of
  /// stopping on its edge (a seam is not a boundary).
  std::array<bool, N> periodic{};
};

/// x with periodic components wrapped into [lo, hi) and the others clamped to [lo, hi].
template <int N>
Eigen::Matrix<double, N, 1> ClampOrWrap(const Eigen::Matrix<double, N, 1>& x,
                                        const Eigen::Matrix<double, N, 1>& lo,
                                        const Eigen::Matrix<double, N, 1>& hi,
                                        const std::array<bool, N>& periodic) {
  Eigen::Matrix<double, N, 1> y;
  for (int i = 0; i < N; ++i) {
    if (periodic[static_cast<size_t>(i)]) {
      const double w = hi[i] - lo[i];
      double t = x[i] - lo[i];
      t -= std::floor(t / w) * w;
      y[i] = lo[i] + (t < w ? t : 0.0);
    } else {
      y[i] = std::min(std::max(x[i], lo[i]), hi[i]);
    }
  }
  return y;
}

// The system in use: interior equations, or the gradient form with active rows pinned.
template <int N>
void ActiveSystem(const NewtonSystem<N>& s, const std::array<bool, N>& active, bool any_active,
                  Eigen::Matrix<double, N, 1>* r, Eigen::Matrix<double, N, N>* a) {
  if (!any_active) {
    *r = s.F;
    *a = s.J;
    return;
  }
  *r = s.grad;
  *a = s.hess;
  for (int i = 0; i < N; ++i) {
    if (!active[static_cast<size_t>(i)]) continue;
    (*r)[i] = 0.0;
    a->row(i).setZero();
    a->col(i).setZero();
    (*a)(i, i) = 1.0;
  }
}

// Newton step for a r + δ = 0 with a fallback to Levenberg–Marquardt when a is singular.
template <int N>
Eigen::Matrix<double, N, 1> NewtonStep(const Eigen::Matrix<double, N, 1>& r,
                                       const Eigen::Matrix<double, N, N>& a, double scale,
                                       bool* singular, double* rcond) {
  const auto lu = Factor<N>(a);
  *singular = IsSingular<N>(lu, scale, rcond);
  if (!*singular) return lu.solve(-r);
  // Damped least squares: the step of smallest norm that reduces |r| along well-determined
  // directions; a continuum of solutions (concentric spheres) then stays put.
  const Eigen::Matrix<double, N, N> ata = a.transpose() * a;
  const double mu = 1e-10 * std::max(ata.trace() / N, 1e-300);
  return (ata + mu * Eigen::Matrix<double, N, N>::Identity()).ldlt().solve(-a.transpose() * r);
}

/// Runs damped Newton from x0 inside [lo, hi]. `eval(x, &system)` fills the system at x.
template <int N, class Eval>
BoxNewtonResult<N> BoxNewton(Eval&& eval, const Eigen::Matrix<double, N, 1>& x0,
                             const Eigen::Matrix<double, N, 1>& lo,
                             const Eigen::Matrix<double, N, 1>& hi,
                             const BoxNewtonOptions<N>& opt) {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  BoxNewtonResult<N> res;
  const auto& periodic = opt.periodic;
  res.x = ClampOrWrap<N>(x0, lo, hi, periodic);
  const Vec width = (hi - lo).cwiseMax(1e-300);
  NewtonSystem<N> sys;
  eval(res.x, &sys);
  int releases = 0;
  for (res.iterations = 0; res.iterations < opt.max_iterations; ++res.iterations) {
    const bool any = std::any_of(res.active.begin(), res.active.end(), [](bool b) { return b; });
    Vec r;
    Mat a;
    ActiveSystem<N>(sys, res.active, any, &r, &a);
    Vec step = NewtonStep<N>(r, a, sys.scale, &res.singular, &res.rcond);
    if (!step.allFinite()) break;
    // Longest fraction of the step that stays in the box.
    double alpha = 1.0;
    for (int i = 0; i < N; ++i) {
      if (periodic[static_cast<size_t>(i)]) continue;
      if (step[i] > 0 && res.x[i] + step[i] > hi[i])
        alpha = std::min(alpha, (hi[i] - res.x[i]) / step[i]);
      if (step[i] < 0 && res.x[i] + step[i] < lo[i])
        alpha = std::min(alpha, (lo[i] - res.x[i]) / step[i]);
    }
    // Backtrack on the residual norm of the same system (the merit for saddles and maxima too).
    const double r0 = r.norm();
    Vec trial = res.x;
    NewtonSystem<N> tsys;
    double a_try = alpha;
    for (int k = 0; k < 30; ++k) {
      trial = ClampOrWrap<N>(res.x + a_try * step, lo, hi, periodic);
      eval(trial, &tsys);
      Vec rt;
      Mat at;
      ActiveSystem<N>(tsys, res.active, any, &rt, &at);
      if (rt.norm() <= (1.0 - 1e-4 * a_try) * r0 || rt.norm() == 0.0 || a_try < 1e-9) break;
      a_try *= 0.5;
    }
    res.x = trial;
    sys = tsys;  // The accepted trial's evaluation is the next iterate's.
    // Parameters that reached the boundary while the step pushed outward become active.
    bool hit = false;
    for (int i = 0; i < N; ++i) {
      if (res.active[static_cast<size_t>(i)] || periodic[static_cast<size_t>(i)]) continue;
      if ((res.x[i] <= lo[i] && step[i] < 0) || (res.x[i] >= hi[i] && step[i] > 0)) {
        res.active[static_cast<size_t>(i)] = true;
        hit = true;
      }
    }
    if (hit) continue;
    // Converged when the Newton step itself (not a backtracked fraction) is negligible.
    if (step.cwiseQuotient(width).cwiseAbs().maxCoeff() > opt.step_tolerance) continue;
    // Converged for the current active set. Release a boundary parameter when the interior
    // Newton step points back into the domain (the extremum is not on this boundary).
    if (any && releases < 2 * N) {
      double rc = 0.0;
      bool sing = false;
      const Vec free_step = NewtonStep<N>(sys.F, sys.J, sys.scale, &sing, &rc);
      bool released = false;
      for (int i = 0; i < N; ++i) {
        if (!res.active[static_cast<size_t>(i)]) continue;
        const bool inward =
            (res.x[i] <= lo[i] && free_step[i] > 0) || (res.x[i] >= hi[i] && free_step[i] < 0);
        if (inward) {
          res.active[static_cast<size_t>(i)] = false;
          released = true;
        }
      }
      if (released) {
        ++releases;
        continue;
      }
    }
    res.converged = true;
    ++res.iterations;
    break;
  }
  return res;
}

}  // namespace tangent::contact::internal
