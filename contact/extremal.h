#pragma once

#include <array>

#include <Eigen/Core>

#include "contact/placed.h"
#include "nurbs/surface.h"

namespace tangent::contact {

struct PairCharts;  // contact/charted_pair.h

/// How an extremal-distance solve ended.
enum class ExtremalStatus {
  kConverged,     ///< an interior extremum, to the step tolerance
  kAtBoundary,    ///< the extremum wants to leave the domain: the extremum restricted to it
  kSingular,      ///< converged, but the Newton matrix is singular there (focal point, or a
                  ///< continuum of extremal pairs): the point is one of many / unstable
  kNotConverged,  ///< iteration budget exhausted; the best point is returned
  /// A seed or a pose was not finite (a NaN parameter, a zero or NaN quaternion): no Newton
  /// step was taken; u is the seed with its non-finite components replaced by the domain's
  /// middle, distances are +inf, points zero and frames the identity (never NaN).
  kInvalidInput,
};
/// The extremum's type from the second-order conditions of ½|f − g|² on the free parameters.
enum class ExtremumKind { kMinimum, kSaddle, kMaximum, kDegenerate };

const char* ToString(ExtremalStatus s);
const char* ToString(ExtremumKind k);

/// Which extremum a solve looks for.
enum class Seek {
  /// The extremum of the distance a contact means: a minimum, interior or on the domain's
  /// boundary (an edge, a corner), for separated or touching pairs; for interpenetrating pairs
  /// the penetration extremum Newton converges to from the seed (a saddle of ½|d|²). When
  /// Newton from the seed ends elsewhere (a saddle or maximum of a separated pair, a boundary
  /// point whose multiplier has the wrong sign, no convergence), a bound-constrained
  /// minimization (projected Newton, then a Newton polish on the active face) restarts from the
  /// seed and its answer is taken if it is a minimum.
  kMinimum,
  /// Whatever extremum Newton converges to from the seed (any kind; boundary parameters
  /// released when the interior step points back inside). For tests and classification.
  kNearest,
};

struct ExtremalOptions {
  int max_iterations = 40;
  double step_tolerance = 1e-13;  ///< Newton step / domain width; ~500 ulp of a unit domain
  Seek seek = Seek::kMinimum;
  /// How well a cold seed is known, as a fraction of each domain width (surface pairs under
  /// Seek::kMinimum). When the seed's neighbourhood of ±neighbourhood reaches a domain edge,
  /// the edges and corners in it are searched as well (their closest samples become further
  /// starts, contact/neighbourhood.h) and the nearest minimum reached from the seed or any of
  /// them is the answer: a boundary minimum whose basin is too thin for the seed is not missed. 0:
  /// off, for re-solves that continue a known extremum (kContinuation).
  double neighbourhood = 0.1;
};

/// The options of a re-solve that continues a known extremum (the tracker's and the servo's
/// re-solves, the global stage's refinement of its own seeds): the seed is the extremum's own
/// last parameters, and a nearer minimum elsewhere in its neighbourhood is another contact,
/// which the global stage finds, not this one.
inline constexpr ExtremalOptions kContinuation{.neighbourhood = 0.0};

/// Everything about a surface pair at parameters u = (u, v, s, t) and poses, in the world:
/// the contact-regular equations F(u) = [d·g_s, d·g_t, N_f·g_s, N_f·g_t] (d = f − g, N_f = f_u ×
/// f_v) and their Jacobian, and the gradient/Hessian of ½|d|². At an extremum with d ≠ 0 the
/// zeros of F are those of design.md §4.1's ∇½|d|² = [d·f_u, d·f_v, −d·g_s, −d·g_t]; unlike
/// that gradient, F keeps a regular Jacobian when the surfaces touch (β = 0), where the
/// gradient's Hessian degenerates to a rank-2 JᵀJ. See docs/contact.md.
struct SurfacePairEval {
  PlacedSurfacePoint f, g;
  Eigen::Vector3d d;  ///< f − g, world
  Eigen::Vector4d F;
  Eigen::Matrix4d F_u;
  Eigen::Vector4d grad;
  Eigen::Matrix4d hess;
};

/// Evaluates the pair (allocation free): the surfaces, F and F_u, and, when `gradient_form`
/// (what boundary handling and classification need), grad and hess too.
void EvaluatePair(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                  const nurbs::NurbsSurface& g, const BodyPose& pose_g, const Eigen::Vector4d& u,
                  nurbs::SpanHint* hint_f, nurbs::SpanHint* hint_g, SurfacePairEval* out,
                  bool gradient_form = true);
/// Fills d, F, F_u (and grad, hess when `gradient_form`) from the surface points already in
/// *out (evaluated in their parameters, or in a pole's chart: contact/pole_chart.h).
void PairEquations(SurfacePairEval* out, bool gradient_form = true);
/// Fills e->grad and e->hess from the surface points already in *e.
void FillGradientForm(SurfacePairEval* e);

/// An extremal pair of points of two surfaces.
struct SurfaceSurfaceExtremum {
  Eigen::Vector4d u;  ///< (u, v) on f, (s, t) on g, inside both domains
  /// Signed distance (m): > 0 apart, < 0 interpenetrating. d·n_g at an interior extremum; at a
  /// boundary one (d no longer along a normal) |d| signed by the side (BoundarySide).
  double beta = 0.0;
  /// Unit vector along which beta is measured (beta = d·direction): n_g at an interior
  /// extremum, ±d/|d| at a boundary one (n_g when d = 0).
  Eigen::Vector3d direction;
  Eigen::Vector3d p_f, p_g;  ///< contact points, world (m)
  Eigen::Vector3d n_g;       ///< unit outward normal of g at p_g, world
  Eigen::Matrix3d R_WCf;     ///< contact frame of f at p_f (ContactFrame; NaN at a pole)
  Eigen::Matrix3d R_WCg;     ///< contact frame of g at p_g
  double alignment = 0.0;    ///< n_f·n_g: −1 for surfaces facing each other
  ExtremalStatus status = ExtremalStatus::kNotConverged;
  ExtremumKind kind = ExtremumKind::kDegenerate;
  std::array<bool, 4> at_bound{};  ///< parameters held on their domain boundary
  int iterations = 0;
  double rcond = 0.0;  ///< of the final Newton matrix
};

/// A seed (u, v, s, t) for SolveSurfaceSurface that cannot miss a boundary minimum
/// (contact/closest_pair.cc): the closest pair among (n+1) x (n+1) samples of each placed
/// surface (an even parameter grid with its edges and corners, n ≥ 1), solved from there; when
/// that solve ends apart, each domain edge is solved as a curve–surface problem and each corner
/// as a point–surface problem from its own closest samples, and a minimum of theirs nearer than
/// the four-parameter answer is returned instead. *distance gets the closest samples' distance.
/// For loading and tests (it allocates and costs (n+1)^4 distance evaluations).
Eigen::Vector4d ClosestSamplePair(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const BodyPose& pose_g, int n,
                                  double* distance = nullptr);

/// Extremal distance between surface f on body F and surface g on body G from a seed (u,v,s,t)
/// (clamped into the domains). Never returns parameters outside the domains. Allocation free.
/// `at_solution` (optional) receives the pair's evaluation at the returned parameters (the
/// solver's last one: a caller needing the surfaces there need not evaluate them again).
SurfaceSurfaceExtremum SolveSurfaceSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                           const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                                           const Eigen::Vector4d& seed,
                                           const ExtremalOptions& options = {},
                                           SurfacePairEval* at_solution = nullptr);

/// Distance between two parameter points (u, v, s, t) of a pair: the largest of the four
/// differences as a fraction of its domain's width, periodic directions the short way round.
double ParameterDistance(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                         const Eigen::Vector4d& x, const Eigen::Vector4d& y);

/// Distances closer than this (m) are one point's: the rounding of |d| for parts of metres.
inline constexpr double kSamePointDistance = 1e-15;

/// A full solve from a tracked contact's parameters that ends farther than this (a fraction of
/// a domain, ParameterDistance) has left the contact's neighbourhood: the tracker's own bound on
/// one correction (TrackerOptions::max_correction).
inline constexpr double kMaxResolveJump = 0.05;

/// Whether a solve from a tracked contact's parameters `from` found another extremum of the
/// pair (the far side of a wire, the other branch of a nearly degenerate contact) rather than
/// the contact moved: it ended more than kMaxResolveJump away and farther apart than the two
/// points at `from` are now (`held_distance` = |f − g| there, which bounds the surfaces'
/// distance from above, so an extremum beyond it is not their nearest pair). A far solve that
/// ends nearer (a ball turned a long way in one step) is the contact moved. Taking another
/// extremum would make β jump up, and a line search step through the surfaces.
bool FoundAnotherExtremum(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                          const Eigen::Vector4d& from, const SurfaceSurfaceExtremum& solved,
                          double held_distance);

/// The contact equations' scaled residual at a pair evaluation with signed distance beta:
/// |d·g_s|, |d·g_t| over L·max(|β|, 1e-3 L) with L = max(|g_s|, |g_t|), and |N_f·g_s|,
/// |N_f·g_t| over |N_f| L (angles in radians). The tracker's and ExtremumAt's one measure.
double ScaledContactResidual(const SurfacePairEval& e, double beta);

/// The extremum record at parameters u that are already an interior extremal pair (e.g. a
/// ContactTracker's corrected parameters): one evaluation of the pair, no Newton step. Status
/// kConverged when the contact equations' scaled residual there is below `tolerance` (the
/// tracker's measure: |d·x_g|, |d·y_g| over the pair's length scale, |n_f·x_g|, |n_f·y_g| in
/// radians), else kNotConverged (the caller then solves). Allocation free.
/// `charts` (optional): sides evaluated in their pole's chart (a ContactTracker's charts()).
SurfaceSurfaceExtremum ExtremumAt(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                  const nurbs::NurbsSurface& g, const BodyPose& pose_g,
                                  const Eigen::Vector4d& u, double tolerance,
                                  SurfacePairEval* at_solution, const PairCharts* charts = nullptr);

/// Extremal distance between a world point x and surface f on a body: d = f − x,
/// equations [d·f_u, d·f_v] (regular at d = 0, where the Jacobian is the first fundamental form).
struct PointSurfaceExtremum {
  Eigen::Vector2d u;
  /// (x − f)·n_f: > 0 when x is on the outward side (m); at a boundary extremum |x − f| signed
  /// by that side.
  double distance = 0.0;
  Eigen::Vector3d p_f;
  Eigen::Matrix3d R_WCf;  ///< contact frame of f at p_f
  ExtremalStatus status = ExtremalStatus::kNotConverged;
  ExtremumKind kind = ExtremumKind::kDegenerate;
  std::array<bool, 2> at_bound{};
  int iterations = 0;
};
/// `at_solution` as for SolveSurfaceSurface.
PointSurfaceExtremum SolvePointSurface(const Eigen::Vector3d& x_W, const nurbs::NurbsSurface& f,
                                       const BodyPose& pose_f, const Eigen::Vector2d& seed,
                                       const ExtremalOptions& options = {},
                                       PlacedSurfacePoint* at_solution = nullptr);

/// Curve g(τ) on body G against surface f on body F: unknowns (u, v, τ), d = g − f, equations
/// [d·f_u, d·f_v, N_f·g'] (regular at contact, as for surface pairs).
struct CurveSurfaceEval {
  PlacedSurfacePoint f;
  PlacedCurvePoint g;
  Eigen::Vector3d d;  ///< g − f, world
  Eigen::Vector3d F;
  Eigen::Matrix3d F_u;
  Eigen::Vector3d grad;
  Eigen::Matrix3d hess;
};
void EvaluateCurveSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f, const BodyCurve& g,
                          const BodyPose& pose_g, const Eigen::Vector3d& u, nurbs::SpanHint* hint_f,
                          int* span_g, nurbs::SpanHint* hint_g, CurveSurfaceEval* out);

/// The form a contact between trimmed faces takes (contact/trimmed.h; seed 001's three trimming
/// constraints, with either face's edge): the faces' extremum, f's edge against g's face, g's
/// edge against f's face, or f's edge against g's edge.
enum class TrimmedForm { kFace, kEdgeOfF, kEdgeOfG, kEdgeEdge };

struct CurveSurfaceExtremum {
  Eigen::Vector3d u = Eigen::Vector3d::Zero();  ///< (u, v) on f, τ on the curve
  /// (g − f)·n_f: > 0 when the curve is outside f (m); at a boundary extremum |g − f| signed by
  /// that side.
  double beta = 0.0;
  Eigen::Vector3d p_f = Eigen::Vector3d::Zero(), p_g = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_WCf = Eigen::Matrix3d::Identity();  ///< contact frame of f at p_f
  ExtremalStatus status = ExtremalStatus::kNotConverged;
  ExtremumKind kind = ExtremumKind::kDegenerate;
  std::array<bool, 3> at_bound{};
  int iterations = 0;
};
CurveSurfaceExtremum SolveCurveSurface(const nurbs::NurbsSurface& f, const BodyPose& pose_f,
                                       const BodyCurve& g, const BodyPose& pose_g,
                                       const Eigen::Vector3d& seed,
                                       const ExtremalOptions& options = {});

/// Pair parameters (u, v, s, t) moved into both surfaces' domains: wrapped round in a periodic
/// direction, clamped elsewhere.
Eigen::Vector4d IntoPairDomain(const nurbs::NurbsSurface& f, const nurbs::NurbsSurface& g,
                               const Eigen::Vector4d& u);

/// The sign of a boundary extremum's distance: which side of the surfaces d = f − g lies on.
/// By g's normal when d is more along it than along f's, else by f's (d·n_f < 0 is apart for a
/// facing pair); +1 when d = 0. At an interior extremum, where d ∥ n_g, it is sign(d·n_g).
double BoundarySide(const Eigen::Vector3d& d, const Eigen::Vector3d& n_f,
                    const Eigen::Vector3d& n_g);

namespace internal {
/// The record of the pair evaluation e at parameters u as an interior extremum: points, frames,
/// β = d·n_g along n_g, alignment (callers override β and direction at a boundary).
void FillPairFields(const SurfacePairEval& e, const Eigen::Vector4d& u,
                    SurfaceSurfaceExtremum* out);
/// Kind from the eigenvalues of a Hessian restricted to the free parameters; eigenvalues below
/// 1e-6 of max(scale, largest eigenvalue) count as zero (scale: the first fundamental forms').
template <int N>
ExtremumKind Classify(const Eigen::Matrix<double, N, N>& hess, const std::array<bool, N>& active,
                      double scale);
}  // namespace internal

}  // namespace tangent::contact
