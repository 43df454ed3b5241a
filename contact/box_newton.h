#pragma once

// Damped Newton on a box (the parameter domains), shared by the extremal-distance solvers.
// Internal header: templated on the problem size N (2, 3, 4), fixed-size Eigen only, so a call
// allocates nothing.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

namespace tangent::contact::internal {

/// What a problem provides at x: the interior system (equations regular at contact) and the
/// gradient / Hessian of ½|d|², used when some parameters sit on the domain boundary.
template <int N>
struct NewtonSystem {
  double value = 0.0;  ///< ½|d|², the objective of the bound-constrained minimization
  Eigen::Matrix<double, N, 1> F;
  Eigen::Matrix<double, N, N> J;
  Eigen::Matrix<double, N, 1> grad;
  Eigen::Matrix<double, N, N> hess;
  /// Natural size of the Newton matrix's entries (e.g. |S_u|² for a point problem), or 0. A
  /// matrix whose entries are all below kSingularRcond · scale is singular even when it is
  /// well conditioned relative to itself (a focal point shrinks a Hessian isotropically).
  double scale = 0.0;
  /// The scale Classify compares the Hessian's pivots with (the first fundamental forms').
  double classify_scale = 0.0;
  /// The pair interpenetrates here (its extremum of interest is then a saddle of ½|d|², which
  /// the bound-constrained minimization must not replace with the crossing's zero distance).
  bool penetrating = false;
  /// The pair touches here: the two points coincide to rounding (|d| ≤ kTouchingDistance of the
  /// problem's size) and the normals are parallel (tangent surfaces, not a crossing). At β = 0
  /// the Newton matrix loses rank (the four tangents lie in one plane, and d's curvature terms
  /// vanish), so Newton and the minimization only creep toward such a point; it is as exact as
  /// the evaluation, and both solvers stop on it as converged.
  bool touching = false;
};

/// |d| below this fraction of the problem's size (coordinates and first-form lengths): the
/// points coincide to the evaluation's rounding (parts of 30 mm: 1e-16 m). So tight because
/// along the tangent plane the pair is fixed only to sqrt(2 R |d|): 1e-15 keeps it below 1 nm.
inline constexpr double kTouchingDistance = 1e-15;
/// |n_f × n_g| below this (unit normals): tangent, not crossing.
inline constexpr double kTouchingSine = 1e-5;

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

/// lu⁻¹ b for a many-column b (a Jacobian's 14 columns): the inverse by N vector solves, then
/// one coefficient-wise product. lu.solve(b) on a matrix takes Eigen's blocked triangular
/// solve, whose packing cost 5,000 instructions for a 3 x 14 right-hand side (callgrind).
template <int N, int M>
Eigen::Matrix<double, N, M> SolveColumns(const Eigen::FullPivLU<Eigen::Matrix<double, N, N>>& lu,
                                         const Eigen::Matrix<double, N, M>& b) {
  Eigen::Matrix<double, N, N> inverse;
  for (int i = 0; i < N; ++i) inverse.col(i) = lu.solve(Eigen::Matrix<double, N, 1>::Unit(i));
  return inverse.lazyProduct(b);
}

/// A Newton step below this fraction of the domain that no longer lowers the residual ends the
/// iteration as converged: stagnation at rounding level, where the step is the matrix's
/// amplification of eps (1e-13 near a sphere's pole, rcond 3e-5). Since J·step = −r, the
/// residual is then below 1e-10 of |J|·width as well.
inline constexpr double kStagnationStep = 1e-10;

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
  /// Parameters held on their bound from the start (they must lie on it).
  std::array<bool, N> initial_active{};
  /// The release test for a held parameter. false: the interior Newton step on F points back
  /// into the domain (any extremum kind). true: the multiplier sign of a minimum of ½|d|², i.e.
  /// the gradient points inward (−∂φ/∂x_i > 0 at a lower bound, < 0 at an upper one).
  bool release_by_gradient = false;
};

/// Whether a held parameter's multiplier has the sign of a minimum: at a lower bound the
/// objective must grow inward (∂φ/∂x_i ≥ 0), at an upper bound ∂φ/∂x_i ≤ 0.
template <int N>
bool HoldsAsMinimum(const Eigen::Matrix<double, N, 1>& x, const Eigen::Matrix<double, N, 1>& grad,
                    const Eigen::Matrix<double, N, 1>& lo, const Eigen::Matrix<double, N, 1>& hi,
                    int i) {
  return (x[i] <= lo[i] && grad[i] >= 0.0) || (x[i] >= hi[i] && grad[i] <= 0.0);
}

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
  for (int i = 0; i < N; ++i) {
    const size_t k = static_cast<size_t>(i);
    res.active[k] =
        opt.initial_active[k] && !periodic[k] && (res.x[i] <= lo[i] || res.x[i] >= hi[i]);
  }
  eval(res.x, &sys);
  int releases = 0;
  for (res.iterations = 0; res.iterations < opt.max_iterations; ++res.iterations) {
    if (sys.touching) {  // (the last evaluation is at res.x)
      res.converged = true;
      res.singular = false;
      break;
    }
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
    double r_trial = r0;
    // A step already at rounding level is not halved: when it does not lower the residual, no
    // fraction of it will by more than rounding. (Halving it to 1e-9 cost 30 evaluations at the
    // end of every warm trim-edge solve of the imported peg: 75,000 instructions a solve.)
    const bool tiny = step.cwiseQuotient(width).cwiseAbs().maxCoeff() < kStagnationStep;
    for (int k = 0; k < 30; ++k) {
      trial = ClampOrWrap<N>(res.x + a_try * step, lo, hi, periodic);
      eval(trial, &tsys);
      Vec rt;
      Mat at;
      ActiveSystem<N>(tsys, res.active, any, &rt, &at);
      r_trial = rt.norm();
      if (r_trial <= (1.0 - 1e-4 * a_try) * r0 || r_trial == 0.0 || a_try < 1e-9 || tiny) break;
      a_try *= 0.5;
    }
    // Stagnation at rounding level: no fraction of a tiny step lowers the residual. Near a
    // pole or another ill-conditioned point the step's own rounding noise (~eps/rcond of the
    // domain) can sit just above step_tolerance for ever; the iterate is as good as it gets.
    if (!(r_trial < r0) && tiny) {
      eval(res.x, &sys);  // leave the evaluation at the iterate
      res.converged = true;
      ++res.iterations;
      break;
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
      Vec free_step = Vec::Zero();
      if (!opt.release_by_gradient) {
        double rc = 0.0;
        bool sing = false;
        free_step = NewtonStep<N>(sys.F, sys.J, sys.scale, &sing, &rc);
      }
      bool released = false;
      for (int i = 0; i < N; ++i) {
        if (!res.active[static_cast<size_t>(i)]) continue;
        const bool inward = opt.release_by_gradient ? !HoldsAsMinimum<N>(res.x, sys.grad, lo, hi, i)
                                                    : (res.x[i] <= lo[i] && free_step[i] > 0) ||
                                                          (res.x[i] >= hi[i] && free_step[i] < 0);
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

/// Minimizes φ = ½|d|² over the box by projected Newton (Bertsekas 1982): parameters on a bound
/// whose gradient points out of the box move by projected gradient, the others by Newton on a
/// Hessian made positive definite (eigenvalues replaced by their magnitudes, so a saddle is left
/// along its negative curvature), along the projection arc with an Armijo test on φ. It only
/// descends, so from any start it ends at a point satisfying the box's first-order conditions
/// (free gradient zero, held gradients pointing out): the interior, edge or corner minimum of
/// the basin it starts in. Linear at a touching pair (φ's Hessian has rank 2 there), so callers
/// polish with BoxNewton from its result. `active` on return: the parameters it holds.
template <int N, class Eval>
BoxNewtonResult<N> BoxMinimize(Eval&& eval, const Eigen::Matrix<double, N, 1>& x0,
                               const Eigen::Matrix<double, N, 1>& lo,
                               const Eigen::Matrix<double, N, 1>& hi,
                               const BoxNewtonOptions<N>& opt) {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  const auto& periodic = opt.periodic;
  BoxNewtonResult<N> res;
  res.x = ClampOrWrap<N>(x0, lo, hi, periodic);
  const Vec width = (hi - lo).cwiseMax(1e-300);
  NewtonSystem<N> sys, trial_sys;
  eval(res.x, &sys);
  auto holds = [&](const Vec& x, const Vec& g, int i, double eps) {
    if (periodic[static_cast<size_t>(i)]) return false;
    return (x[i] - lo[i] <= eps && g[i] > 0.0) || (hi[i] - x[i] <= eps && g[i] < 0.0);
  };
  const int budget = 4 * opt.max_iterations;
  for (res.iterations = 0; res.iterations < budget; ++res.iterations) {
    if (sys.touching) {  // (the last evaluation is at res.x)
      res.converged = true;
      break;
    }
    const Vec& g = sys.grad;
    // Diagonal scaling for the held parameters' gradient steps.
    const double floor = std::max(1e-12 * sys.hess.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    Vec dscale;
    for (int i = 0; i < N; ++i) dscale[i] = 1.0 / std::max(std::abs(sys.hess(i, i)), floor);
    // ε-active set: on a bound or within the projected-gradient step of it, gradient outward.
    const Vec pg = ClampOrWrap<N>(res.x - dscale.cwiseProduct(g), lo, hi, periodic) - res.x;
    std::array<bool, N> held{};
    for (int i = 0; i < N; ++i) {
      const double eps = std::min(1e-3 * width[i], std::abs(pg[i]) + 1e-15 * width[i]);
      held[static_cast<size_t>(i)] = holds(res.x, g, i, eps);
    }
    Mat h = sys.hess;
    for (int i = 0; i < N; ++i) {
      if (!held[static_cast<size_t>(i)]) continue;
      h.row(i).setZero();
      h.col(i).setZero();
      h(i, i) = 1.0;
    }
    const Eigen::SelfAdjointEigenSolver<Mat> eig(h);
    Vec lam = eig.eigenvalues().cwiseAbs();
    const double lam_floor = std::max(1e-10 * lam.maxCoeff(), 1e-300);
    lam = lam.cwiseMax(lam_floor);
    Vec gf = g;
    for (int i = 0; i < N; ++i) {
      if (held[static_cast<size_t>(i)]) gf[i] = 0.0;
    }
    Vec step = -(eig.eigenvectors() * (eig.eigenvectors().transpose() * gf).cwiseQuotient(lam));
    for (int i = 0; i < N; ++i) {
      if (held[static_cast<size_t>(i)]) step[i] = -dscale[i] * g[i];
    }
    if (!step.allFinite()) break;
    // Armijo along the projection arc.
    double alpha = 1.0;
    Vec trial = res.x;
    bool accepted = false;
    for (int k = 0; k < 40; ++k) {
      trial = ClampOrWrap<N>(res.x + alpha * step, lo, hi, periodic);
      Vec moved = trial - res.x;
      for (int i = 0; i < N; ++i) {  // a wrapped periodic move counts by its short way round
        if (periodic[static_cast<size_t>(i)]) moved[i] = alpha * step[i];
      }
      eval(trial, &trial_sys);
      const double decrease = g.dot(moved);
      if (trial_sys.value <= sys.value + 1e-4 * decrease && decrease <= 0.0) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
    }
    const double moved = (trial - res.x).cwiseQuotient(width).cwiseAbs().maxCoeff();
    if (!accepted) break;  // no descent left at this precision: a first-order point
    res.x = trial;
    sys = trial_sys;
    if (moved < opt.step_tolerance) {
      res.converged = true;
      ++res.iterations;
      break;
    }
  }
  // The held set at the end: on a bound with the gradient pointing out.
  for (int i = 0; i < N; ++i) {
    res.active[static_cast<size_t>(i)] = !periodic[static_cast<size_t>(i)] &&
                                         HoldsAsMinimum<N>(res.x, sys.grad, lo, hi, i) &&
                                         (res.x[i] <= lo[i] || res.x[i] >= hi[i]);
  }
  return res;
}

}  // namespace tangent::contact::internal
