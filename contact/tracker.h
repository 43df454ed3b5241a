#pragma once

#include <array>

#include <Eigen/Core>

#include "contact/charted_pair.h"
#include "contact/contact_jacobian.h"
#include "contact/extremal.h"

namespace tangent::contact {

/// Outcome of one tracking step. Inside the servo loop nothing throws: a failure is a state.
enum class TrackStatus {
  kTracked,     ///< predicted and corrected; residual small
  kAtBoundary,  ///< the extremum reached a domain edge: parameters clamped there
  kSingular,    ///< ∂F/∂u singular at the point (focal point, continuum): u_q not updated
  kLost,        ///< the corrector did not contract; the contact must be re-found globally
};
const char* ToString(TrackStatus s);

struct TrackerOptions {
  /// Lost when the corrector step exceeds this fraction of a domain width (the predictor
  /// should land within Newton's quadratic basin; a larger jump means a different extremum).
  double max_correction = 0.05;
  /// Lost when the contact equations' scaled residual at the predicted point exceeds this
  /// (|d·x_g|, |d·y_g| over the pair's length scale, and |n_f·x_g|, |n_f·y_g| in radians):
  /// one Newton step from a residual r leaves about r², so 1e-3 still corrects to ~1e-6 and
  /// the next step's prediction finishes the job.
  double max_residual = 1e-3;
  /// Newton corrector steps per Step() (0–3): 0 takes the predicted point as it is, each step
  /// costs one more evaluation of the pair. u_q and β come from the last evaluated point.
  int corrector_steps = 1;
};

/// Follows one extremal pair of two surfaces as the bodies move (seed 001 §3.3, design.md §2
/// step 2): predictor u += u_q Δq, Newton correctors on the contact equations (one by default,
/// TrackerOptions::corrector_steps), and the closed-form u_q refreshed from the last evaluation.
/// Holds pointers to the surfaces (which must outlive it) and fixed-size state only: Step()
/// and Rebind() allocate nothing and never throw.
///
/// Next to a smooth pole a side is followed in the pole's tangent-plane chart (contact/
/// pole_chart.h: taken within kChartEnter of the domain, left beyond kChartLeave): there its
/// parameters are degenerate (u_q unbounded at the pole, the angle swinging half a turn as the
/// point crosses it), while the chart is regular, so a contact is followed on, next to and
/// across a pole like anywhere else.
class ContactTracker {
 public:
  ContactTracker(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                 const TrackerOptions& options = {});

  /// Follows another pair of surfaces from now on (a contact slot moved to another face pair,
  /// optimizer/body_contacts.h): not tracking until the next Reset.
  void Rebind(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g);

  /// Starts from an extremum u (from SolveSurfaceSurface) at poses q_f, q_g.
  TrackStatus Reset(const Vector7d& q_f, const Vector7d& q_g, const Eigen::Vector4d& u);
  /// One servo step to new poses.
  TrackStatus Step(const Vector7d& q_f, const Vector7d& q_g);

  /// The pair's parameters (u, v, s, t).
  const Eigen::Vector4d& u() const { return params_; }
  /// u_q at the last evaluated point (the predicted point of the last step): first-order
  /// accurate at u(), which is what the next prediction needs. A charted side's rows are its
  /// chart coordinates' (charts()).
  const Matrix4x14& u_q() const { return u_q_; }
  /// The sides followed in a pole's chart (for ExtremumAt at u()).
  const PairCharts& charts() const { return charts_; }
  /// Signed distance at the last evaluated point, corrected to first order: β + β_u δ.
  double beta() const { return beta_; }
  double residual() const { return residual_; }
  TrackStatus status() const { return status_; }

 private:
  /// Evaluates at u_ (and corrects it when `correct`); `jacobian`: refresh u_q there.
  TrackStatus Evaluate(const Vector7d& q_f, const Vector7d& q_g, bool correct,
                       bool jacobian = true);
  /// params_ from the coordinates u_ (through the charts' inverses); false when a charted
  /// point has no parameters (it left its chart's reach).
  bool ToParameters();
  /// Takes or leaves each side's chart by the hysteresis bounds, converting u_ and u_q_.
  void SwitchCharts();
  /// Side k's surface (0: f, 1: g) and span hint.
  const nurbs::NurbsSurface& Surface(int k) const { return k == 0 ? *f_ : *g_; }
  nurbs::SpanHint* Hint(int k) { return k == 0 ? &hint_f_ : &hint_g_; }

  const nurbs::NurbsSurface* f_;
  const nurbs::NurbsSurface* g_;
  TrackerOptions options_;
  Eigen::Vector4d lo_, hi_;
  std::array<bool, 4> periodic_{};
  Vector7d q_f_, q_g_;
  /// The coordinates followed: a charted side's chart coordinates, the other's parameters.
  Eigen::Vector4d u_ = Eigen::Vector4d::Zero();
  Eigen::Vector4d params_ = Eigen::Vector4d::Zero();
  SurfacePoles poles_[2];
  PairCharts charts_;
  Matrix4x14 u_q_ = Matrix4x14::Zero();
  nurbs::SpanHint hint_f_, hint_g_;
  SurfacePairEval eval_;
  double beta_ = 0.0;
  double residual_ = 0.0;
  TrackStatus status_ = TrackStatus::kLost;
};

}  // namespace tangent::contact
