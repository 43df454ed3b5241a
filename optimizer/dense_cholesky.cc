#include "optimizer/dense_cholesky.h"

#include <algorithm>
#include <cmath>

namespace tangent::optimizer {

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
      const double* ui = U + i * n;
      double dot = 0.0;
      for (Eigen::Index k = std::max(start, first_[static_cast<size_t>(i)]); k < i; ++k) {
        dot += ui[k] * uj[k];
      }
      const double v = (aj[i] - dot) / ui[i];
      uj[i] = v;
      sq += v * v;
    }
    const double pivot = aj[j] - sq;
    if (!(pivot > 0.0)) return false;  // (NaN too)
    uj[j] = std::sqrt(pivot);
  }
  return true;
}

void DenseCholesky::SolveInPlace(Eigen::VectorXd* x_io) const {
  const Eigen::Index n = U_.rows();
  const double* U = U_.data();
  double* x = x_io->data();
  // Uᵀ y = x: y_j = (x_j − U(0:j, j)·y(0:j)) / U(j, j).
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* uj = U + j * n;
    double dot = 0.0;
    for (Eigen::Index k = first_[static_cast<size_t>(j)]; k < j; ++k) dot += uj[k] * x[k];
    x[j] = (x[j] - dot) / uj[j];
  }
  // U x = y, by columns: x_j = y_j / U(j, j), then y(0:j) −= x_j U(0:j, j).
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const double* uj = U + j * n;
    x[j] /= uj[j];
    const double xj = x[j];
    for (Eigen::Index k = first_[static_cast<size_t>(j)]; k < j; ++k) x[k] -= xj * uj[k];
  }
}

}  // namespace tangent::optimizer
