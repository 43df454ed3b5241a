#include "nurbs/bezier_nets.h"

#include <algorithm>

namespace tangent::nurbs::internal {

void DerivativeBezierRows(const KnotVector& k, int mu, int a, AlphaRow* rows) {
  const int p = k.degree();
  double factor = 1.0;
  for (int r = 0; r < a; ++r) factor *= p - r;
  double x[kMaxDegree];
  for (int i = 0; i <= p - a; ++i) {
    for (int r = 0; r < p; ++r) x[r] = r < p - a - i ? k[mu] : k[mu + 1];
    OsloAlphaRow(k, mu, x, &rows[i], a);
    for (int j = 0; j <= p; ++j) rows[i][static_cast<size_t>(j)] *= factor;
  }
}

std::vector<int> DomainSpans(const KnotVector& k) {
  std::vector<int> spans;
  for (int mu = k.degree(); mu < k.num_basis(); ++mu) {
    if (k[mu] < k[mu + 1]) spans.push_back(mu);
  }
  return spans;
}

void SurfaceBezierNet(const KnotVector& ku, const KnotVector& kv,
                      const std::vector<Eigen::Vector4d>& cpw, int mu_u, int mu_v, int du, int dv,
                      double scale, Eigen::Vector4d* net) {
  const int p = ku.degree();
  const int q = kv.degree();
  const int num_v = kv.num_basis();
  AlphaRow ru[kMaxDegree + 1], rv[kMaxDegree + 1];
  DerivativeBezierRows(ku, mu_u, du, ru);
  DerivativeBezierRows(kv, mu_v, dv, rv);
  for (int a = 0; a <= p - du; ++a) {
    for (int b = 0; b <= q - dv; ++b) {
      Eigen::Vector4d acc = Eigen::Vector4d::Zero();
      for (int i = 0; i <= p; ++i) {
        Eigen::Vector4d row = Eigen::Vector4d::Zero();
        for (int j = 0; j <= q; ++j) {
          row += rv[b][static_cast<size_t>(j)] *
                 cpw[static_cast<size_t>((mu_u - p + i) * num_v + (mu_v - q + j))];
        }
        acc += ru[a][static_cast<size_t>(i)] * row;
      }
      net[a * (q + 1 - dv) + b] = scale * acc;
    }
  }
}

SpanFormSurface BuildSpanForm(const KnotVector& ku, const KnotVector& kv,
                              const std::vector<Eigen::Vector4d>& cpw, double scale) {
  const int p = ku.degree();
  const int q = kv.degree();
  std::vector<Eigen::Vector4d> nets;
  nets.reserve(static_cast<size_t>(SpanFormSurface::NetPointsPerSpan(p, q)) *
               DomainSpans(ku).size() * DomainSpans(kv).size());
  for (int mu_u : DomainSpans(ku)) {
    for (int mu_v : DomainSpans(kv)) {
      for (const auto& f : SpanFormSurface::kFamilies) {
        if (f[0] > p || f[1] > q) continue;
        nets.resize(nets.size() + static_cast<size_t>((p + 1 - f[0]) * (q + 1 - f[1])));
        SurfaceBezierNet(ku, kv, cpw, mu_u, mu_v, f[0], f[1], scale,
                         nets.data() + nets.size() - (p + 1 - f[0]) * (q + 1 - f[1]));
      }
    }
  }
  return SpanFormSurface(p, q, ku.Breakpoints(), kv.Breakpoints(), nets);
}

template <int Dim>
SpanFormCurve<Dim> BuildSpanForm(const KnotVector& k,
                                 const std::vector<Eigen::Matrix<double, Dim + 1, 1>>& cpw) {
  using HPoint = Eigen::Matrix<double, Dim + 1, 1>;
  const int p = k.degree();
  std::vector<HPoint> nets;
  for (int mu : DomainSpans(k)) {
    for (int d = 0; d <= std::min(kMaxOrder, p); ++d) {
      nets.resize(nets.size() + static_cast<size_t>(p + 1 - d));
      CurveBezierNet(k, cpw, mu, d, nets.data() + nets.size() - (p + 1 - d));
    }
  }
  return SpanFormCurve<Dim>(p, k.Breakpoints(), nets);
}

template SpanFormCurve<2> BuildSpanForm<2>(const KnotVector&, const std::vector<Eigen::Vector3d>&);
template SpanFormCurve<3> BuildSpanForm<3>(const KnotVector&, const std::vector<Eigen::Vector4d>&);

}  // namespace tangent::nurbs::internal
