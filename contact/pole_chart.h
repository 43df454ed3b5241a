#pragma once

// The tangent-plane chart at a smooth pole (docs/contact.md, "Pole charts").
//
// At a pole row (a domain edge the parameterization collapses to one point P) the surface is
// smooth but its parameters are not: S_u = 0 along the row, so Newton's matrix in (u, v) is
// singular there and linear near it, the contact Jacobian u_q blows up, and a point crossing the
// pole jumps half a turn in its angle parameter. Near P the surface is a graph over its tangent
// plane, so the plane's coordinates are a regular chart there:
//
//   (x, y) = T (S(u, v) − P),   T = [e1 e2]ᵀ,  e1, e2 orthonormal ⟂ n (the limit normal at P).
//
// Its partials follow from the parameters' by the inverse function theorem, written so that
// nothing is divided by the vanishing S_u: with ρ the distance from the row in the across
// parameter and U = S_a/ρ (a the angle parameter; U → ∂S_a/∂ρ at the row),
//
//   A = [T U, T S_ρ],  M = A⁻¹,  [S_x S_y] = [U S_ρ] M,
//   S_ij = (I − [S_x S_y] T) Q_ij,  Q_ij = S_aa m_i m_j / ρ² + S_aρ (m_i r_j + m_j r_i) / ρ
//                                          + S_ρρ r_i r_j,
//
// with (m_x, m_y) and (r_x, r_y) M's rows (the second partials lie along n: T S(x, y) is linear).
// Allocation free.

#include <Eigen/Core>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::contact {

/// A smooth pole's tangent-plane chart, in the surface's own (body) frame.
struct PoleChart {
  int across = -1;      ///< the parameter across the row (1: v = bound, 0: u = bound); −1: none
  double bound = 0.0;   ///< the row's value of that parameter
  double inward = 1.0;  ///< +1 at the lower bound, −1 at the upper
  double width = 1.0;   ///< the across parameter's domain width
  double length = 1.0;  ///< |∂S/∂ρ| at the pole times width: the surface's size across (m)
  Eigen::Vector3d P = Eigen::Vector3d::Zero();   ///< the pole point
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();  ///< the limit unit normal there (outward)
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitY();  ///< e1 × e2 = n
  bool valid() const { return across >= 0; }
  /// Distance from the row in the across parameter (≥ 0 inside the domain).
  double Rho(const Eigen::Vector2d& uv) const { return inward * (uv[across] - bound); }
};

/// Where a chart is used: a tracked point takes it within kChartEnter of the across domain from
/// the row and keeps it until kChartLeave (hysteresis: a point on the zone's edge does not switch
/// back and forth); a solve from a seed within kChartSolve runs in it; both give it up beyond
/// kChartReach, or where the surface's normal turns more than 60° from the pole's (ChartHolds:
/// the surface is then no longer a graph over the tangent plane that the chart can follow).
/// Generous, because Newton in the parameters suffers well before the pole: a sphere's contact
/// 0.03 in v from it (6° of latitude) is not corrected to 1e-12 in one tracker step that is at the
/// equator.
inline constexpr double kChartEnter = 0.1;
inline constexpr double kChartLeave = 0.15;
inline constexpr double kChartSolve = 0.1;
inline constexpr double kChartReach = 0.25;
/// The cosine of the largest angle between the surface's normal and the pole's in a chart.
inline constexpr double kChartNormalCosine = 0.5;

/// The chart of the smooth pole row within `fraction` of the domain from uv, if there is one
/// (a vertex pole, such as a cone's apex, has no tangent plane and no chart). Costs a few
/// evaluations when uv is that near a domain edge, nothing otherwise.
bool FindPoleChart(const nurbs::NurbsSurface& s, const Eigen::Vector2d& uv, double fraction,
                   PoleChart* chart);

/// The smooth poles of a surface's domain edges, found once (a tracker's, when it is bound to a
/// pair), so that looking for a chart along the way costs no evaluation.
struct SurfacePoles {
  PoleChart edge[4];  ///< index 2 × across + (1 at the upper bound); invalid where no pole
  bool any = false;
  void Find(const nurbs::NurbsSurface& s);
  /// The chart whose pole lies within `fraction` of the domain from uv, or nullptr.
  const PoleChart* Near(const Eigen::Vector2d& uv, double fraction) const;
};

/// Whether the chart may follow the surface at uv: within kChartReach of the pole, and the
/// normal there within 60° of the pole's. One evaluation.
bool ChartHolds(const nurbs::NurbsSurface& s, const PoleChart& chart, const Eigen::Vector2d& uv,
                nurbs::SpanHint* hint);

/// How well the chart's partials resolve the normal at uv (radians): near the pole U = S_a/ρ
/// divides the rounding of S_a (~eps |P|, the homogeneous sums' size) by ρ, and nearer than
/// kLimitRho its limit is off by O(ρ). A contact's equations cannot be checked finer there than
/// this (ExtremumAt's floor for a charted side); 1e-15 or less beyond 1e-4 of the domain.
double ChartPrecision(const PoleChart& chart, const Eigen::Vector2d& uv);

/// The chart coordinates of the surface point at uv.
Eigen::Vector2d ChartCoordinates(const nurbs::NurbsSurface& s, const PoleChart& chart,
                                 const Eigen::Vector2d& uv, nurbs::SpanHint* hint);

/// The parameters of the surface point with chart coordinates xy (the chart's inverse): Newton in
/// (angle, ρ) from `guess`'s angle or, when that points elsewhere (the point crossed the pole),
/// from the best of the row's sampled directions. False when no point of the domain maps there
/// (the angle parameter is not periodic and xy lies outside its range).
bool ChartParameters(const nurbs::NurbsSurface& s, const PoleChart& chart,
                     const Eigen::Vector2d& xy, const Eigen::Vector2d& guess, nurbs::SpanHint* hint,
                     Eigen::Vector2d* uv);

/// ∂(x, y)/∂(u, v) at uv: converts a parameter velocity into the chart's.
Eigen::Matrix2d ChartFromParameters(const nurbs::NurbsSurface& s, const PoleChart& chart,
                                    const Eigen::Vector2d& uv, nurbs::SpanHint* hint);

/// The surface at uv with its partials taken in the chart, (u, v) → (x, y) (out->charted): the
/// same record EvaluatePlaced fills, regular at the pole itself.
void EvaluateCharted(const nurbs::NurbsSurface& s, const PoleChart& chart, const BodyPose& pose,
                     const Eigen::Vector2d& uv, nurbs::SpanHint* hint, PlacedSurfacePoint* out);

}  // namespace tangent::contact
