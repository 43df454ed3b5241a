#include "optimizer/dense_cholesky.h"

#include <cmath>

namespace tangent::optimizer {

bool DenseCholesky::Compute(const Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  if (U_.rows() != n || U_.cols() != n) U_.resize(n, n);  // (sized by Reserve on the servo)
  double* U = U_.data();
  const double* a = A.data();
  // Column by column (up-looking): U(i, j) = (A(i, j) − U(0:i, i)·U(0:i, j)) / U(i, i), then
  // U(j, j) = √(A(j, j) − |U(0:j, j)|²). Both columns are contiguous in column-major storage.
  for (Eigen::Index j = 0; j < n; ++j) {
    double* uj = U + j * n;
    const double* aj = a + j * n;
    double sq = 0.0;
    for (Eigen::Index i = 0; i < j; ++i) {
      const double* ui = U + i * n;
      double dot = 0.0;
      for (Eigen::Index k = 0; k < i; ++k) dot += ui[k] * uj[k];
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
    for (Eigen::Index k = 0; k < j; ++k) dot += uj[k] * x[k];
    x[j] = (x[j] - dot) / uj[j];
  }
  // U x = y, by columns: x_j = y_j / U(j, j), then y(0:j) −= x_j U(0:j, j).
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const double* uj = U + j * n;
    x[j] /= uj[j];
    const double xj = x[j];
    for (Eigen::Index k = 0; k < j; ++k) x[k] -= xj * uj[k];
  }
}

}  // namespace tangent::optimizer
