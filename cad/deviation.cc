#include "cad/deviation.h"

#include <ShapeAnalysis_Surface.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>

#include <algorithm>

namespace tangent::cad {

double FaceDeviation(const nurbs::NurbsSurface& ours, const nurbs::TrimmedDomain* trim,
                     const Handle(Geom_Surface) & theirs, int n) {
  ShapeAnalysis_Surface analysis(theirs);
  const double u0 = ours.knots_u().domain_begin(), u1 = ours.knots_u().domain_end();
  const double v0 = ours.knots_v().domain_begin(), v1 = ours.knots_v().domain_end();
  double worst = 0.0;
  bool have_previous = false;
  gp_Pnt2d previous;
  auto measure = [&](double u, double v) {
    const Eigen::Vector3d s = ours.Evaluate(u, v, 0).S;
    const gp_Pnt p(s[0], s[1], s[2]);
    // The projection's tolerance: rounding of the point's coordinates, so that a deviation of
    // 1e-9 of the part's size is resolved.
    const double precision = 1e-13 * std::max(1.0, s.norm());
    const gp_Pnt2d foot = have_previous ? analysis.NextValueOfUV(previous, p, precision)
                                        : analysis.ValueOfUV(p, precision);
    worst = std::max(worst, theirs->Value(foot.X(), foot.Y()).Distance(p));
    previous = foot;
    have_previous = true;
  };
  for (int i = 0; i <= n; ++i) {
    have_previous = false;
    for (int j = 0; j <= n; ++j) {
      const double u = u0 + (u1 - u0) * i / n, v = v0 + (v1 - v0) * j / n;
      if (trim && !trim->Contains(Eigen::Vector2d(u, v))) {
        have_previous = false;
        continue;
      }
      measure(u, v);
    }
  }
  if (trim) {
    for (const nurbs::TrimLoop& loop : trim->loops()) {
      for (const nurbs::NurbsCurve2d& c : loop.curves) {
        have_previous = false;
        const double t0 = c.knots().domain_begin(), t1 = c.knots().domain_end();
        for (int k = 0; k < 8; ++k) {
          const Eigen::Vector2d uv = c.Evaluate(t0 + (t1 - t0) * (k + 0.5) / 8.0, 0).C;
          measure(std::clamp(uv[0], u0, u1), std::clamp(uv[1], v0, v1));
        }
      }
    }
  }
  return worst;
}

}  // namespace tangent::cad
