#include "optimizer/dense_cholesky.h"

#include <algorithm>
#include <cmath>

namespace tangent::optimizer {

namespace {

// x(k0:k1) · y(k0:k1) in two interleaved partial sums: the multiply–adds of one sum wait on each
// other's latency, two chains overlap.
inline double Dot(const double* x, const double* y, Eigen::Index k0, Eigen::Index k1) {
  double d0 = 0.0, d1 = 0.0;
  Eigen::Index k = k0;
  for (; k + 1 < k1; k += 2) {
    d0 += x[k] * y[k];
    d1 += x[k + 1] * y[k + 1];
  }
  if (k < k1) d0 += x[k] * y[k];
  return d0 + d1;
}

}  // namespace

// Columns j0 … j0 + C − 1 of U (those before them done). Their rows above j0 depend only on
// the columns before j0: C independent chains of dot products, run side by side row by row
// (one column alone is a chain of dependent dot products, bound by their latency). Each
// column's operations are in the same order as alone: the same factor to the bit.
template <int C>
[[gnu::always_inline]] inline bool DenseCholesky::Columns(const double* a, Eigen::Index n,
                                                          Eigen::Index j0) {
  double* U = U_.data();
  double* u[C];
  const double* ac[C];
  Eigen::Index start[C];
  double sq[C];
  Eigen::Index lowest = j0;
#pragma GCC unroll 4
  for (int c = 0; c < C; ++c) {
    const Eigen::Index j = j0 + c;
    u[c] = U + j * n;
    ac[c] = a + j * n;
    Eigen::Index s = 0;
    while (s < j && ac[c][s] == 0.0) u[c][s++] = 0.0;
    start[c] = s;
    first_[static_cast<size_t>(j)] = s;
    lowest = std::min(lowest, s);
    sq[c] = 0.0;
  }
  for (Eigen::Index i = lowest; i < j0; ++i) {
    const double* ui = U + i * n;
    const Eigen::Index fi = first_[static_cast<size_t>(i)];
    const double inv = inverse_diagonal_[static_cast<size_t>(i)];
#pragma GCC unroll 4
    for (int c = 0; c < C; ++c) {
      if (i < start[c]) continue;
      const double v = (ac[c][i] - Dot(ui, u[c], std::max(start[c], fi), i)) * inv;
      u[c][i] = v;
      sq[c] += v * v;
    }
  }
  // The group's own triangle, column after column.
  for (int c = 0; c < C; ++c) {
    const Eigen::Index j = j0 + c;
    for (Eigen::Index i = std::max(j0, start[c]); i < j; ++i) {
      const double v =
          (ac[c][i] - Dot(U + i * n, u[c], std::max(start[c], first_[static_cast<size_t>(i)]), i)) *
          inverse_diagonal_[static_cast<size_t>(i)];
      u[c][i] = v;
      sq[c] += v * v;
    }
    const double pivot = ac[c][j] - sq[c];
    if (!(pivot > 0.0)) return false;  // (NaN too)
    u[c][j] = std::sqrt(pivot);
    inverse_diagonal_[static_cast<size_t>(j)] = 1.0 / u[c][j];
  }
  return true;
}

bool DenseCholesky::Compute(const Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  if (U_.rows() != n || U_.cols() != n) Reserve(static_cast<int>(n));  // (done on the servo)
  const double* a = A.data();
  // Column by column (up-looking): U(i, j) = (A(i, j) − U(0:i, i)·U(0:i, j)) / U(i, i), then
  // U(j, j) = √(A(j, j) − |U(0:j, j)|²). Both columns are contiguous in column-major storage.
  // A column's leading zeros stay zeros in U (by induction on i: each U(i, j) above the first
  // nonzero A(i, j) is a sum over zeros), so each column starts at its first nonzero: exact,
  // and where bodies are coupled along a chain (a Newton matrix's 7 x 7 blocks are zero between
  // bodies no term couples) most of the work is above that start. The four-bar's 21 x 21:
  // 693 multiply–adds in the dot products instead of 1,330. Columns go in groups of four
  // (Columns: independent chains side by side).
  Eigen::Index j0 = 0;
  if (n <= 8) {  // (one body: chains this short gain less than the grouping costs)
    for (; j0 < n; ++j0) {
      if (!Columns<1>(a, n, j0)) return false;
    }
    return true;
  }
  for (; j0 + 4 <= n; j0 += 4) {
    if (!Columns<4>(a, n, j0)) return false;
  }
  switch (n - j0) {
    case 3:
      return Columns<3>(a, n, j0);
    case 2:
      return Columns<2>(a, n, j0);
    case 1:
      return Columns<1>(a, n, j0);
    default:
      return true;
  }
}

void DenseCholesky::SolveInPlace(Eigen::VectorXd* x_io) const {
  const Eigen::Index n = U_.rows();
  const double* U = U_.data();
  double* x = x_io->data();
  // Uᵀ y = x: y_j = (x_j − U(0:j, j)·y(0:j)) / U(j, j).
  for (Eigen::Index j = 0; j < n; ++j) {
    x[j] = (x[j] - Dot(U + j * n, x, first_[static_cast<size_t>(j)], j)) *
           inverse_diagonal_[static_cast<size_t>(j)];
  }
  // U x = y, by columns: x_j = y_j / U(j, j), then y(0:j) −= x_j U(0:j, j).
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const double* uj = U + j * n;
    x[j] *= inverse_diagonal_[static_cast<size_t>(j)];
    const double xj = x[j];
    for (Eigen::Index k = first_[static_cast<size_t>(j)]; k < j; ++k) x[k] -= xj * uj[k];
  }
}

}  // namespace tangent::optimizer
