#include "contact/tracker.h"

#include <Eigen/LU>  // Matrix4d::computeInverseAndDetWithCheck

#include "contact/box_newton.h"
#include "contact/solver_inputs.h"

namespace tangent::contact {

const char* ToString(TrackStatus s) {
  switch (s) {
    case TrackStatus::kTracked:
      return "tracked";
    case TrackStatus::kAtBoundary:
      return "at_boundary";
    case TrackStatus::kSingular:
      return "singular";
    case TrackStatus::kLost:
      return "lost";
  }
  return "?";
}

ContactTracker::ContactTracker(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                               const TrackerOptions& options)
    : options_(options) {
  Rebind(f, g);
}

void ContactTracker::Rebind(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g) {
  f_ = &f;
  g_ = &g;
  const internal::PairBox box = internal::PairBoxOf(f, g);
  lo_ = box.lo;
  hi_ = box.hi;
  periodic_ = box.periodic;
  poles_[0].Find(f);
  poles_[1].Find(g);
  charts_ = {};
  hint_f_ = {};
  hint_g_ = {};
  u_q_.setZero();
  status_ = TrackStatus::kLost;
}

TrackStatus ContactTracker::Reset(const Vector7d& q_f, const Vector7d& q_g,
                                  const Eigen::Vector4d& u) {
  params_ = internal::ClampOrWrap<4>(u, lo_, hi_, periodic_);
  u_ = params_;
  charts_ = {};
  u_q_.setZero();
  SwitchCharts();  // a side next to a smooth pole starts in its chart
  return Evaluate(q_f, q_g, /*correct=*/false);
}

bool ContactTracker::ToParameters() {
  for (int k = 0; k < 2; ++k) {
    const PoleChart& c = charts_.side[k];
    if (!c.valid()) {
      params_.segment<2>(2 * k) = u_.segment<2>(2 * k);
      continue;
    }
    Eigen::Vector2d uv;
    if (!ChartParameters(Surface(k), c, u_.segment<2>(2 * k), params_.segment<2>(2 * k), Hint(k),
                         &uv) ||
        c.Rho(uv) > kChartReach * c.width) {
      return false;
    }
    params_.segment<2>(2 * k) = uv;
  }
  return true;
}

void ContactTracker::SwitchCharts() {
  for (int k = 0; k < 2; ++k) {
    const nurbs::NurbsSurface& s = Surface(k);
    nurbs::SpanHint* hint = Hint(k);
    const Eigen::Vector2d uv = params_.segment<2>(2 * k);
    PoleChart& c = charts_.side[k];
    if (c.valid()) {
      if (c.Rho(uv) <= kChartLeave * c.width) continue;
      // Leaving: u_q's rows from the chart's coordinates back to the parameters.
      const Eigen::Matrix2d D = ChartFromParameters(s, c, uv, hint);
      const Eigen::Matrix<double, 2, 14> rows = D.inverse() * u_q_.middleRows<2>(2 * k);
      u_q_.middleRows<2>(2 * k) = rows;
      u_.segment<2>(2 * k) = uv;
      c = PoleChart{};
    } else if (const PoleChart* near = poles_[k].Near(uv, kChartEnter);
               near && ChartHolds(s, *near, uv, hint)) {
      const Eigen::Matrix2d D = ChartFromParameters(s, *near, uv, hint);
      const Eigen::Matrix<double, 2, 14> rows = D * u_q_.middleRows<2>(2 * k);
      u_q_.middleRows<2>(2 * k) = rows;
      u_.segment<2>(2 * k) = ChartCoordinates(s, *near, uv, hint);
      c = *near;
    }
  }
}

TrackStatus ContactTracker::Step(const Vector7d& q_f, const Vector7d& q_g) {
  // Predictor: first-order motion of the extremal point with the bodies.
  Eigen::Matrix<double, 14, 1> dq;
  dq << q_f - q_f_, q_g - q_g_;
  u_ += u_q_ * dq;
  if (!ToParameters()) {
    status_ = TrackStatus::kLost;
    return status_;
  }
  if (options_.corrector_steps <= 0) {
    // No corrector: only the residual tells a prediction that left the basin.
    const TrackStatus s = Evaluate(q_f, q_g, /*correct=*/false);
    if (s == TrackStatus::kTracked && residual_ > options_.max_residual)
      status_ = TrackStatus::kLost;
    return status_;
  }
  // The corrector steps before the last need no u_q: only the last evaluation's is kept.
  for (int k = 1; k < options_.corrector_steps; ++k) {
    const TrackStatus s = Evaluate(q_f, q_g, /*correct=*/true, /*jacobian=*/false);
    if (s == TrackStatus::kLost || s == TrackStatus::kSingular) return s;
  }
  return Evaluate(q_f, q_g, /*correct=*/true);
}

TrackStatus ContactTracker::Evaluate(const Vector7d& q_f, const Vector7d& q_g, bool correct,
                                     bool jacobian) {
  q_f_ = q_f;
  q_g_ = q_g;
  // A charted side's coordinates are its chart's: no bound, measured against its size.
  std::array<bool, 4> charted{};
  Eigen::Vector4d size = hi_ - lo_;
  for (int k = 0; k < 2; ++k) {
    if (!charts_.side[k].valid()) continue;
    charted[2 * k] = charted[2 * k + 1] = true;
    size.segment<2>(2 * k).setConstant(charts_.side[k].length);
  }
  bool clamped = false;
  for (int i = 0; i < 4; ++i) {
    const size_t k = static_cast<size_t>(i);
    if (!charted[k] && !periodic_[k] && (params_[i] < lo_[i] || params_[i] > hi_[i]))
      clamped = true;
  }
  params_ = internal::ClampOrWrap<4>(params_, lo_, hi_, periodic_);
  for (int i = 0; i < 4; ++i) {
    if (!charted[static_cast<size_t>(i)]) u_[i] = params_[i];
  }
  const BodyPose pf = BodyPose::FromCoordinates(q_f);
  const BodyPose pg = BodyPose::FromCoordinates(q_g);
  EvaluatePairCharted(*f_, pf, *g_, pg, params_, charts_, &hint_f_, &hint_g_, &eval_,
                      /*gradient_form=*/false);
  // Eigen's fixed-size 4 x 4 inverse (cofactors, vectorized) gives the corrector and the
  // determinant together, faster than an LU here; a matrix near singular is caught by the guard
  // below and by the closed form's conditioning test, so cofactor rounding is never relied on
  // where the matrix is ill conditioned.
  Eigen::Matrix4d inverse;
  double det = 0.0;
  bool invertible = false;
  eval_.F_u.computeInverseAndDetWithCheck(inverse, det, invertible, 0.0);
  const Eigen::Vector3d n_g = eval_.g.unit_normal();  // the limit normal at a pole
  beta_ = eval_.d.dot(n_g);
  residual_ = ScaledContactResidual(eval_, beta_);
  // A cheap guard before solving (the determinant against the product of the row sizes, which
  // bounds it); the closed form below applies the solver's kSingularRcond and refuses too.
  const double det_scale = eval_.F_u.cwiseAbs().rowwise().maxCoeff().prod();
  if (!invertible || !(std::abs(det) > 1e-13 * det_scale)) {
    status_ = TrackStatus::kSingular;
    return status_;
  }
  if (correct) {
    Eigen::Vector4d delta = -(inverse * eval_.F);
    // A parameter on its domain edge whose correction points outward stays on the edge: the
    // extremum restricted to the boundary is then corrected with the gradient of ½|d|² on the
    // free parameters (as SolveSurfaceSurface does).
    std::array<bool, 4> active{};
    bool any = false;
    for (int i = 0; i < 4; ++i) {
      active[static_cast<size_t>(i)] =
          !charted[static_cast<size_t>(i)] && !periodic_[static_cast<size_t>(i)] &&
          ((u_[i] <= lo_[i] && delta[i] < 0) || (u_[i] >= hi_[i] && delta[i] > 0));
      any = any || active[static_cast<size_t>(i)];
    }
    if (any) {
      FillGradientForm(&eval_);
      internal::NewtonSystem<4> sys;
      sys.F = eval_.F;
      sys.J = eval_.F_u;
      sys.grad = eval_.grad;
      sys.hess = eval_.hess;
      Eigen::Vector4d r;
      Eigen::Matrix4d a;
      internal::ActiveSystem<4>(sys, active, true, &r, &a);
      double rcond = 0.0;
      bool singular = false;
      delta = internal::NewtonStep<4>(r, a, 0.0, &singular, &rcond);
      clamped = true;
    }
    if (!delta.allFinite() ||
        delta.cwiseQuotient(size).cwiseAbs().maxCoeff() > options_.max_correction ||
        (!any && residual_ > options_.max_residual)) {
      status_ = TrackStatus::kLost;
      return status_;
    }
    // β at the corrected point to first order: ∂β/∂u = n_g·[f_u f_v −g_s −g_t].
    beta_ += n_g.dot(eval_.f.world.S_u * delta[0] + eval_.f.world.S_v * delta[1] -
                     eval_.g.world.S_u * delta[2] - eval_.g.world.S_v * delta[3]);
    u_ += delta;
    if (!ToParameters()) {
      status_ = TrackStatus::kLost;
      return status_;
    }
    params_ = internal::ClampOrWrap<4>(params_, lo_, hi_, periodic_);
    for (int i = 0; i < 4; ++i) {
      if (!charted[static_cast<size_t>(i)]) u_[i] = params_[i];
    }
  }
  if (jacobian && !ContactJacobianClosedForm(eval_, pf, pg, &u_q_)) {
    status_ = TrackStatus::kSingular;
    return status_;
  }
  status_ = clamped ? TrackStatus::kAtBoundary : TrackStatus::kTracked;
  if (jacobian) SwitchCharts();
  return status_;
}

}  // namespace tangent::contact
