// The area of a trimmed surface (area.h).

#include "nurbs/area.h"

#include "nurbs/primitives.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace tangent::nurbs {

namespace {

constexpr int kGauss = 12;

// Gauss–Legendre nodes and weights on [0, 1] (Newton on the Legendre polynomial).
struct Rule {
  std::array<double, kGauss> x{}, w{};
  Rule() {
    for (int i = 0; i < kGauss; ++i) {
      double z = std::cos(M_PI * (i + 0.75) / (kGauss + 0.5)), dp = 1.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = z;
        for (int k = 2; k <= kGauss; ++k) {
          const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = kGauss * (z * p1 - p0) / (z * z - 1.0);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[static_cast<size_t>(i)] = 0.5 * (1.0 - z);
      w[static_cast<size_t>(i)] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

const Rule& Gauss() {
  static const Rule rule;
  return rule;
}

// The distinct knots of a knot vector's domain.
std::vector<double> Breaks(const KnotVector& k) {
  std::vector<double> out;
  for (double t : k.knots()) {
    if (t < k.domain_begin() || t > k.domain_end()) continue;
    if (out.empty() || t > out.back()) out.push_back(t);
  }
  return out;
}

class Integrator {
 public:
  explicit Integrator(const NurbsSurface& s)
      : s_(s), ub_(Breaks(s.knots_u())), vb_(Breaks(s.knots_v())) {}

  double Jacobian(double u, double v) const {
    const SurfacePoint p = s_.Evaluate(u, v, 1);
    return p.S_u.cross(p.S_v).norm();
  }

  // G(u, v) = ∫_{u0}^{u} |S_u × S_v|(s, v) ds, span by span.
  double G(double u, double v) const {
    const Rule& r = Gauss();
    double sum = 0.0;
    for (size_t i = 0; i + 1 < ub_.size() && ub_[i] < u; ++i) {
      const double a = ub_[i], b = std::min(ub_[i + 1], u);
      for (int q = 0; q < kGauss; ++q) {
        sum += (b - a) * r.w[static_cast<size_t>(q)] *
               Jacobian(a + (b - a) * r.x[static_cast<size_t>(q)], v);
      }
    }
    return sum;
  }

  // ∫ G(c(t)) v'(t) dt over a curve, cut where it crosses a knot line of the surface.
  double Contour(const NurbsCurve2d& c) const {
    std::vector<double> cuts;
    const std::vector<double> tb = Breaks(c.knots());
    for (size_t i = 0; i + 1 < tb.size(); ++i) {
      constexpr int kSamples = 64;
      double t_prev = tb[i];
      Eigen::Vector2d p_prev = c.Evaluate(t_prev, 0).C;
      cuts.push_back(t_prev);
      for (int k = 1; k <= kSamples; ++k) {
        const double t = tb[i] + (tb[i + 1] - tb[i]) * k / kSamples;
        const Eigen::Vector2d p = c.Evaluate(t, 0).C;
        for (int d = 0; d < 2; ++d) {
          for (double line : d == 0 ? ub_ : vb_) {
            if (p[d] == line) cuts.push_back(t);  // on the line: a cut there
            if ((p_prev[d] - line) * (p[d] - line) >= 0.0) continue;
            double a = t_prev, b = t;  // bisection to the crossing
            for (int it = 0; it < 60 && b - a > 1e-15 * (1.0 + std::abs(a)); ++it) {
              const double m = 0.5 * (a + b);
              ((c.Evaluate(m, 0).C[d] - line) * (p_prev[d] - line) > 0.0 ? a : b) = m;
            }
            cuts.push_back(0.5 * (a + b));
          }
        }
        t_prev = t;
        p_prev = p;
      }
    }
    cuts.push_back(tb.back());
    std::sort(cuts.begin(), cuts.end());
    const Rule& r = Gauss();
    double sum = 0.0;
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
      const double a = cuts[i], b = cuts[i + 1];
      if (b <= a) continue;
      for (int q = 0; q < kGauss; ++q) {
        const CurvePoint<2> p = c.Evaluate(a + (b - a) * r.x[static_cast<size_t>(q)], 1);
        sum += (b - a) * r.w[static_cast<size_t>(q)] * G(p.C[0], p.C[1]) * p.C1[1];
      }
    }
    return sum;
  }

 private:
  const NurbsSurface& s_;
  std::vector<double> ub_, vb_;
};

}  // namespace

double TrimmedArea(const NurbsSurface& surface, const TrimmedDomain* trim) {
  const Integrator in(surface);
  double area = 0.0;
  const double u1 = surface.knots_u().domain_end();
  const double v0 = surface.knots_v().domain_begin(), v1 = surface.knots_v().domain_end();
  if (trim == nullptr || !trim->has_outer()) {
    // The domain's boundary, counter-clockwise: only its right side (u = u1) has G ≠ 0 and dv ≠ 0.
    area += in.Contour(MakePolyline2d({{u1, v0}, {u1, v1}}));
  }
  if (trim != nullptr) {
    for (const TrimLoop& loop : trim->loops()) {
      for (const NurbsCurve2d& c : loop.curves) area += in.Contour(c);
    }
  }
  return area;
}

}  // namespace tangent::nurbs
