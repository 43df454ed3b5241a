#include "nurbs/span_form.h"

#include "nurbs/span_kernels.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace tangent::nurbs {

namespace internal {

bool HasAvx2Fma() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return has;
}

int FindInterval(const std::vector<double>& breaks, double x, int hint) {
  const int last = static_cast<int>(breaks.size()) - 2;
  const double* b = breaks.data();
  // Coherent calls (a tracked contact) stay in their span: one predictable comparison.
  if (hint >= 0 && hint <= last && b[hint] <= x && x < b[hint + 1]) return hint;
  // Otherwise a branchless binary search: its trip count depends only on the span count, and
  // the comparison compiles to a conditional move, so random queries cost no mispredictions
  // (measured: a branchy search cost ~11 ns per random bicubic evaluation, a third of it).
  int base = 0;
  int len = last + 1;
  while (len > 1) {
    const int half = len / 2;
    base = (b[base + half] <= x) ? base + half : base;
    len -= half;
  }
  return base;  // x below the domain or NaN gives 0; x at or past the end gives the last span.
}

Eigen::MatrixXd BezierToPowerMatrix(int p) {
  Eigen::MatrixXd binom = Eigen::MatrixXd::Zero(p + 1, p + 1);
  for (int n = 0; n <= p; ++n) {
    binom(n, 0) = 1.0;
    for (int k = 1; k <= n; ++k)
      binom(n, k) = binom(n - 1, k - 1) + (k <= n - 1 ? binom(n - 1, k) : 0.0);
  }
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(p + 1, p + 1);
  for (int k = 0; k <= p; ++k) {
    for (int i = 0; i <= k; ++i) {
      m(k, i) = binom(p, k) * binom(k, i) * (((k - i) % 2) ? -1.0 : 1.0);
    }
  }
  return m;
}

void BernsteinValues(int p, double s, double b[kMaxOrder + 1][kMaxDegree + 1]) {
  double level[kMaxDegree + 1] = {1.0};
  const double r = 1.0 - s;
  for (int k = 0; k <= p; ++k) {
    if (k > 0) {
      level[k] = s * level[k - 1];
      for (int i = k - 1; i >= 1; --i) level[i] = r * level[i] + s * level[i - 1];
      level[0] = r * level[0];
    }
    const int d = p - k;  // This level is the degree-k row, stored as b[p − k].
    if (d <= kMaxOrder) std::copy(level, level + k + 1, b[d]);
  }
}

// Bernstein-form kernel for degrees above 3 (and for spans whose power form is not exact): the
// span holds the Bezier nets of A and of its partials (already in u, v units), so evaluation
// only contracts with Bernstein values.
template <int Order>
void BernsteinKernel(const Eigen::Vector4d* c, int p, int q, double s, double t, double, double,
                     HomogeneousSurfaceDerivs* out) {
  double bu[kMaxOrder + 1][kMaxDegree + 1], bv[kMaxOrder + 1][kMaxDegree + 1];
  BernsteinValues(p, s, bu);
  BernsteinValues(q, t, bv);
  constexpr int kCount = Order == 0 ? 1 : (Order == 1 ? 3 : 6);
  for (int f = 0; f < kCount; ++f) {
    const int a = SpanFormSurface::kFamilies[f][0];
    const int b = SpanFormSurface::kFamilies[f][1];
    const int nu = p + 1 - a;
    const int nv = q + 1 - b;
    Eigen::Vector4d acc = Eigen::Vector4d::Zero();
    for (int i = 0; i < nu; ++i) {
      Eigen::Vector4d row = Eigen::Vector4d::Zero();
      for (int j = 0; j < nv; ++j) row += bv[b][j] * c[i * nv + j];
      acc += bu[a][i] * row;
    }
    out->A[f] = acc;
    c += std::max(nu, 0) * std::max(nv, 0);
  }
}

template void BernsteinKernel<0>(const Eigen::Vector4d*, int, int, double, double, double, double,
                                 HomogeneousSurfaceDerivs*);
template void BernsteinKernel<1>(const Eigen::Vector4d*, int, int, double, double, double, double,
                                 HomogeneousSurfaceDerivs*);
template void BernsteinKernel<2>(const Eigen::Vector4d*, int, int, double, double, double, double,
                                 HomogeneousSurfaceDerivs*);

bool PowerFormIsExact(const Eigen::Vector4d* power, const Eigen::Vector4d* nets, int p, int q,
                      double inv_hu, double inv_hv, SpanKernel power_kernel) {
  // Cartesian derivatives per order (S; S_u, S_v; S_uu, S_uv, S_vv) of both forms at a 5 x 5
  // grid of the span including its edges, and each order's largest value over the span.
  HomogeneousSurfaceDerivs ha, hb;
  constexpr int kGrid = 5;
  SurfacePoint a[kGrid][kGrid], b[kGrid][kGrid];
  double span_scale[3] = {};
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const double s = i / (kGrid - 1.0), t = j / (kGrid - 1.0);
      power_kernel(power, p, q, s, t, inv_hu, inv_hv, &ha);
      BernsteinKernel<kMaxOrder>(nets, p, q, s, t, inv_hu, inv_hv, &hb);
      RationalQuotient(ha, kMaxOrder, &a[i][j]);
      RationalQuotient(hb, kMaxOrder, &b[i][j]);
      const SurfacePoint& y = b[i][j];
      span_scale[0] = std::max(span_scale[0], y.S.norm());
      span_scale[1] = std::max({span_scale[1], y.S_u.norm(), y.S_v.norm()});
      span_scale[2] = std::max({span_scale[2], y.S_uu.norm(), y.S_uv.norm(), y.S_vv.norm()});
    }
  }
  // Each family relative to its size at the point (as docs/nurbs.md measures), floored at
  // kPointScaleFloor of its largest size on the span: where a family nearly vanishes (a
  // second derivative through zero) no basis resolves it better than that.
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const SurfacePoint &x = a[i][j], &y = b[i][j];
      const double scale[3] = {y.S.norm(), std::max(y.S_u.norm(), y.S_v.norm()),
                               std::max({y.S_uu.norm(), y.S_uv.norm(), y.S_vv.norm()})};
      const double error[3] = {
          (x.S - y.S).norm(), std::max((x.S_u - y.S_u).norm(), (x.S_v - y.S_v).norm()),
          std::max({(x.S_uu - y.S_uu).norm(), (x.S_uv - y.S_uv).norm(), (x.S_vv - y.S_vv).norm()})};
      for (int k = 0; k < 3; ++k) {
        const double at = std::max(scale[k], kPointScaleFloor * span_scale[k]);
        if (!(error[k] <= kPowerFormTolerance * at)) return false;
      }
    }
  }
  return true;
}

namespace {

template <int Order>
SpanFormSurface::Kernel SelectKernel(int p, int q) {
  // Unrolled kernels for the degrees CAD parts use most (planes, quadrics, bicubics).
#define TANGENT_KERNEL_CASE(PP, QQ) \
  if (p == PP && q == QQ) return &SurfaceKernel<PP, QQ, Order>;
  TANGENT_KERNEL_CASE(1, 1)
  TANGENT_KERNEL_CASE(1, 2)
  TANGENT_KERNEL_CASE(2, 1)
  TANGENT_KERNEL_CASE(2, 2)
  TANGENT_KERNEL_CASE(1, 3)
  TANGENT_KERNEL_CASE(3, 1)
  TANGENT_KERNEL_CASE(2, 3)
  TANGENT_KERNEL_CASE(3, 2)
  TANGENT_KERNEL_CASE(3, 3)
#undef TANGENT_KERNEL_CASE
  return &BernsteinKernel<Order>;
}

}  // namespace
}  // namespace internal

int SpanFormSurface::NetPointsPerSpan(int p, int q) {
  int n = 0;
  for (const auto& f : kFamilies) n += std::max(p + 1 - f[0], 0) * std::max(q + 1 - f[1], 0);
  return n;
}

SpanFormSurface::SpanFormSurface(int p, int q, std::vector<double> breaks_u,
                                 std::vector<double> breaks_v,
                                 const std::vector<Eigen::Vector4d>& nets)
    : p_(p), q_(q), breaks_u_(std::move(breaks_u)), breaks_v_(std::move(breaks_v)) {
  const size_t nu = breaks_u_.size() - 1;
  const size_t nv = breaks_v_.size() - 1;
  const size_t in_size = static_cast<size_t>(NetPointsPerSpan(p, q));
  if (nets.size() != nu * nv * in_size) {
    throw std::logic_error("SpanFormSurface: net count does not match the spans");
  }
  for (size_t i = 0; i < nu; ++i) inv_h_u_.push_back(1.0 / (breaks_u_[i + 1] - breaks_u_[i]));
  for (size_t j = 0; j < nv; ++j) inv_h_v_.push_back(1.0 / (breaks_v_[j + 1] - breaks_v_[j]));
  power_ = p <= 3 && q <= 3;
  bicubic_ = p == 3 && q == 3;
  kernels_[0] = internal::SelectKernel<0>(p, q);
  kernels_[1] = internal::SelectKernel<1>(p, q);
  kernels_[2] = internal::SelectKernel<2>(p, q);
  offsets_.resize(nu * nv);
  net_form_.assign(nu * nv, 1);
  if (!power_) {
    patch_size_ = in_size;
    coeffs_ = nets;
    for (size_t span = 0; span < nu * nv; ++span) offsets_[span] = span * in_size;
  } else {
    patch_size_ = static_cast<size_t>((p + 1) * (q + 1));
    const Eigen::MatrixXd mu = internal::BezierToPowerMatrix(p);
    const Eigen::MatrixXd mv = internal::BezierToPowerMatrix(q);
    Eigen::MatrixXd b(p + 1, q + 1);
    std::vector<Eigen::Vector4d> power(patch_size_);
    for (size_t span = 0; span < nu * nv; ++span) {
      const Eigen::Vector4d* net = nets.data() + span * in_size;  // The net of A comes first.
      for (int comp = 0; comp < 4; ++comp) {
        for (int a = 0; a <= p; ++a)
          for (int bb = 0; bb <= q; ++bb) b(a, bb) = net[a * (q + 1) + bb][comp];
        const Eigen::MatrixXd pc = mu * b * mv.transpose();
        for (int a = 0; a <= p; ++a)
          for (int bb = 0; bb <= q; ++bb)
            power[static_cast<size_t>(a * (q + 1) + bb)][comp] = pc(a, bb);
      }
      offsets_[span] = coeffs_.size();
      const double ihu = inv_h_u_[span / nv], ihv = inv_h_v_[span % nv];
      if (internal::PowerFormIsExact(power.data(), net, p, q, ihu, ihv, kernels_[kMaxOrder])) {
        net_form_[span] = 0;
        coeffs_.insert(coeffs_.end(), power.begin(), power.end());
      } else {
        coeffs_.insert(coeffs_.end(), net, net + in_size);  // a short span: its Bezier nets
      }
    }
  }
  avx2_ = bicubic_ && internal::HasAvx2Fma() && !std::getenv("TANGENT_NO_AVX2");
  if (avx2_) {
    for (int order = 0; order <= kMaxOrder; ++order) {
      kernels_[order] = internal::BicubicKernelAvx2(order);
    }
  }
  net_kernels_[0] = &internal::BernsteinKernel<0>;
  net_kernels_[1] = &internal::BernsteinKernel<1>;
  net_kernels_[2] = &internal::BernsteinKernel<2>;
}

namespace {

// Cartesian derivatives C, C', C'' of a homogeneous curve piece (the quotient rule).
template <int Dim>
void CurveQuotient(const HomogeneousCurveDerivs<Dim>& h, Eigen::Matrix<double, Dim, 1> out[3]) {
  const double inv_w = 1.0 / h.A[0][Dim];
  out[0] = h.A[0].template head<Dim>() * inv_w;
  out[1] = (h.A[1].template head<Dim>() - h.A[1][Dim] * out[0]) * inv_w;
  out[2] =
      (h.A[2].template head<Dim>() - 2.0 * h.A[1][Dim] * out[1] - h.A[2][Dim] * out[0]) * inv_w;
}

}  // namespace

template <int Dim>
SpanFormCurve<Dim>::SpanFormCurve(int p, std::vector<double> breaks,
                                  const std::vector<HPoint>& nets)
    : p_(p), breaks_(std::move(breaks)) {
  const size_t n = breaks_.size() - 1;
  const size_t in_size = static_cast<size_t>(NetPointsPerSpan(p));
  if (nets.size() != n * in_size) {
    throw std::logic_error("SpanFormCurve: net count does not match the spans");
  }
  power_ = p <= 3;
  const Eigen::MatrixXd m = internal::BezierToPowerMatrix(p);
  std::vector<HPoint> power(static_cast<size_t>(p + 1));
  for (size_t i = 0; i < n; ++i) {
    inv_h_.push_back(1.0 / (breaks_[i + 1] - breaks_[i]));
    const HPoint* net = nets.data() + i * in_size;
    offsets_.push_back(coeffs_.size());
    net_form_.push_back(1);
    if (power_) {
      for (int k = 0; k <= p; ++k) {
        HPoint c = HPoint::Zero();
        for (int a = 0; a <= k; ++a) c += m(k, a) * net[a];
        power[static_cast<size_t>(k)] = c;
      }
      // The power form only where it reproduces the Bernstein form (a short span does not:
      // internal::kPowerFormTolerance), checked at four points per span.
      double scale[3] = {}, error[3] = {};
      for (double s : {0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0}) {
        HomogeneousCurveDerivs<Dim> ha, hb;
        PowerPiece(power.data(), s, inv_h_.back(), kMaxOrder, &ha);
        NetPiece(net, s, inv_h_.back(), kMaxOrder, &hb);
        Eigen::Matrix<double, Dim, 1> a[3], b[3];
        CurveQuotient<Dim>(ha, a);
        CurveQuotient<Dim>(hb, b);
        for (int k = 0; k <= kMaxOrder && k <= p; ++k) {
          scale[k] = std::max(scale[k], b[k].norm());
          error[k] = std::max(error[k], (a[k] - b[k]).norm());
        }
      }
      bool exact = true;
      for (int k = 0; k <= kMaxOrder; ++k) {
        exact = exact && error[k] <= internal::kPowerFormTolerance * scale[k];
      }
      if (exact) {
        net_form_.back() = 0;
        coeffs_.insert(coeffs_.end(), power.begin(), power.end());
        continue;
      }
    }
    coeffs_.insert(coeffs_.end(), net, net + in_size);
  }
}

template <int Dim>
void SpanFormCurve<Dim>::NetPiece(const HPoint* c, double s, double inv_h, int order,
                                  HomogeneousCurveDerivs<Dim>* out) const {
  (void)inv_h;  // (the hodograph nets are in t units already)
  double b[kMaxOrder + 1][kMaxDegree + 1];
  internal::BernsteinValues(p_, s, b);
  for (int k = 0; k <= order; ++k) {
    out->A[k].setZero();
    for (int a = 0; a <= p_ - k; ++a) out->A[k] += b[k][a] * c[a];
    c += p_ + 1 - k;
  }
}

template <int Dim>
void SpanFormCurve<Dim>::PowerPiece(const HPoint* c, double s, double inv_h, int order,
                                    HomogeneousCurveDerivs<Dim>* out) const {
  HPoint p0 = c[p_];
  HPoint p1 = HPoint::Zero();
  HPoint p2 = HPoint::Zero();
  for (int k = p_ - 1; k >= 0; --k) {
    p2 = p2 * s + p1;
    p1 = p1 * s + p0;
    p0 = p0 * s + c[k];
  }
  out->A[0] = p0;
  if (order >= 1) out->A[1] = p1 * inv_h;
  if (order >= 2) out->A[2] = 2.0 * p2 * inv_h * inv_h;
}

template <int Dim>
void SpanFormCurve<Dim>::Evaluate(double t, int order, int* hint,
                                  HomogeneousCurveDerivs<Dim>* out) const {
  const int i = internal::FindInterval(breaks_, t, *hint);
  *hint = i;
  const double inv_h = inv_h_[static_cast<size_t>(i)];
  const double s = internal::ClampUnit((t - breaks_[static_cast<size_t>(i)]) * inv_h);
  const HPoint* c = coeffs_.data() + offsets_[static_cast<size_t>(i)];
  if (net_form_[static_cast<size_t>(i)]) {
    NetPiece(c, s, inv_h, order, out);
  } else {
    PowerPiece(c, s, inv_h, order, out);
  }
}

template class SpanFormCurve<2>;
template class SpanFormCurve<3>;

}  // namespace tangent::nurbs
