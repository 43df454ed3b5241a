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

bool DenseCholesky::Compute(const Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  if (U_.rows() != n || U_.cols() != n) Reserve(static_cast<int>(n));  // (done on the servo)
  double* U = U_.data();
  const double* a = A.data();
  // Column by column (up-looking): U(i, j) = (A(i, j) − U(0:i, i)·U(0:i, j)) / U(i, i), then
  // U(j, j) = √(A(j, j) − |U(0:j, j)|²). Both columns are contiguous in column-major storage.
  // A column's leading zeros stay zeros in U (by induction on i: each U(i, j) above the first
  // nonzero A(i, j) is a sum over zeros), so each column starts at its first nonzero: exact,
  // and where bodies are coupled along a chain (a Newton matrix's 7 x 7 blocks are zero between
  // bodies no term couples) most of the work is above that start. The four-bar's 21 x 21:
  // 693 multiply–adds in the dot products instead of 1,330.
  for (Eigen::Index j = 0; j < n; ++j) {
    double* uj = U + j * n;
    const double* aj = a + j * n;
    Eigen::Index start = 0;
    while (start < j && aj[start] == 0.0) uj[start++] = 0.0;
    first_[static_cast<size_t>(j)] = start;
    double sq = 0.0;
    for (Eigen::Index i = start; i < j; ++i) {
      const double v =
          (aj[i] - Dot(U + i * n, uj, std::max(start, first_[static_cast<size_t>(i)]), i)) *
          inverse_diagonal_[static_cast<size_t>(i)];
      uj[i] = v;
      sq += v * v;
    }
    const double pivot = aj[j] - sq;
    if (!(pivot > 0.0)) return false;  // (NaN too)
    uj[j] = std::sqrt(pivot);
    inverse_diagonal_[static_cast<size_t>(j)] = 1.0 / uj[j];
  }
  return true;
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
