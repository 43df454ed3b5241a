#pragma once

#include <vector>

#include <Eigen/Core>

namespace tangent::optimizer {

/// Cholesky factorization A = UᵀU of a small dense symmetric matrix stored in its upper
/// triangle (column-major), as Eigen::LLT<MatrixXd, Upper> computes it, for the servo's Newton
/// matrices (14 x 14 for two moving bodies). Eigen's dynamic-size LLT runs a matrix–vector
/// product per column through its general kernels; at these sizes their set-up is most of the
/// work (8,300 instructions for 14 x 14, callgrind on the servo). Here every inner loop is a dot
/// product or an update of two contiguous columns of U, and each column starts at its first
/// nonzero (the envelope, which the factor keeps). Storage is sized by Reserve, so
/// Compute and SolveInPlace never allocate.
class DenseCholesky {
 public:
  /// Sizes the factor's storage for n x n matrices.
  void Reserve(int n) {
    U_.resize(n, n);
    first_.resize(static_cast<size_t>(n));
    inverse_diagonal_.resize(static_cast<size_t>(n));
  }
  /// Factorizes A's upper triangle (A n x n, n as reserved). False, leaving the factor
  /// unusable, when A is not numerically positive definite: a pivot not > 0 (or NaN).
  bool Compute(const Eigen::MatrixXd& A);
  /// x ← A⁻¹ x with the last successful factorization.
  void SolveInPlace(Eigen::VectorXd* x) const;
  /// The upper-triangular factor U (its strictly lower part is not referenced).
  const Eigen::MatrixXd& factor() const { return U_; }

 private:
  template <int C>
  bool Columns(const double* a, Eigen::Index n, Eigen::Index j0);

  Eigen::MatrixXd U_;
  std::vector<Eigen::Index> first_;  ///< per column, its first nonzero row (the envelope)
  /// 1 / U(j, j): the factorization and the solves multiply by it instead of dividing (a
  /// division is ~4x a multiply's latency on the chain each column waits on).
  std::vector<double> inverse_diagonal_;
};

}  // namespace tangent::optimizer
