#include "nurbs/basis.h"

namespace tangent::nurbs {

void BasisDerivatives(const KnotVector& knots, int span, double t, int order, BasisTable* ders) {
  const int p = knots.degree();
  // ndu[j][r]: basis functions (upper triangle incl. diagonal) and knot differences (lower).
  double ndu[kMaxDegree + 1][kMaxDegree + 1];
  double left[kMaxDegree + 1];
  double right[kMaxDegree + 1];
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = t - knots[span + 1 - j];
    right[j] = knots[span + j] - t;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  auto& d = *ders;
  for (int j = 0; j <= p; ++j) d[0][static_cast<size_t>(j)] = ndu[j][p];
  // Derivatives (Piegl & Tiller eq. 2.9) with two alternating rows a[s1], a[s2].
  double a[2][kMaxDegree + 1];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0;
    int s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= order; ++k) {
      double dv = 0.0;
      const int rk = r - k;
      const int pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        dv = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        dv += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        dv += a[s2][k] * ndu[r][pk];
      }
      d[static_cast<size_t>(k)][static_cast<size_t>(r)] = dv;
      const int tmp = s1;
      s1 = s2;
      s2 = tmp;
    }
  }
  double factor = p;
  for (int k = 1; k <= order; ++k) {
    for (int j = 0; j <= p; ++j) d[static_cast<size_t>(k)][static_cast<size_t>(j)] *= factor;
    factor *= (p - k);
  }
}

void OsloAlphaRow(const KnotVector& knots, int mu, const double* x,
                  std::array<double, kMaxDegree + 1>* alpha, int num_delta) {
  const int p = knots.degree();
  auto& a = *alpha;
  // a[b] multiplies c_{mu - r + b} after level r; level 0 is the single coefficient c_mu.
  a[0] = 1.0;
  for (int r = 1; r <= p; ++r) {
    const double xr = x[r - 1];
    // A δ argument keeps only the linear part of the affine weights: −1/(t_{k+r} − t_k) and
    // +1/(t_{k+r} − t_k) instead of (t_{k+r} − x)/(…) and (x − t_k)/(…).
    const bool delta = r > p - num_delta;
    // Row vector times the r x (r+1) bidiagonal B-spline recurrence matrix R_r(xr): row for
    // coefficient k = mu - r + 1 + b spreads to columns k-1 (weight (t_{k+r}-x)/(t_{k+r}-t_k))
    // and k (weight (x-t_k)/(t_{k+r}-t_k)). Walk backwards so a[] can be updated in place.
    a[static_cast<size_t>(r)] = 0.0;
    for (int b = r; b >= 0; --b) {
      double value = 0.0;
      if (b <= r - 1) {
        const int k = mu - r + 1 + b;
        const double num = delta ? -1.0 : knots[k + r] - xr;
        value += a[static_cast<size_t>(b)] * num / (knots[k + r] - knots[k]);
      }
      if (b >= 1) {
        const int k = mu - r + b;
        const double num = delta ? 1.0 : xr - knots[k];
        value += a[static_cast<size_t>(b - 1)] * num / (knots[k + r] - knots[k]);
      }
      a[static_cast<size_t>(b)] = value;
    }
  }
}

}  // namespace tangent::nurbs
