#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace tangent::optimizer {

/// A symmetric matrix of 7 x 7 blocks (one block row and column per moving body) with a fixed
/// block pattern: the diagonal and the body pairs some term couples. Stored densely (small
/// systems) or as an Eigen column-major sparse matrix whose pattern never changes, so a sparse
/// factorization can analyse it once (seed 000 §5.2). Both storages hand out the same writable
/// 7 x 7 block views; nothing allocates after construction.
class BlockMatrix {
 public:
  using BlockRef = Eigen::Map<Eigen::Matrix<double, 7, 7>, 0, Eigen::OuterStride<>>;

  /// `pairs`: coupled block pairs (i, j) (either order, duplicates allowed); the diagonal is
  /// always present.
  BlockMatrix(int num_blocks, const std::vector<std::pair<int, int>>& pairs, bool sparse);

  int num_blocks() const { return num_blocks_; }
  int size() const { return 7 * num_blocks_; }
  bool is_sparse() const { return sparse_; }
  /// The writable block (i, j); it must be in the pattern.
  BlockRef Block(int i, int j);
  /// Adds B to block (i, j) and Bᵀ to (j, i), writing only the upper block triangle (the one
  /// the factorizations read; i == j adds B + Bᵀ). The lower off-diagonal blocks stay zero:
  /// the matrix is symmetric in meaning, upper-triangular in storage. (Upper, because Eigen's
  /// simplicial factorization reads an upper-stored column-major matrix in place; the lower
  /// triangle it would copy into a new matrix on every factorization.)
  void AddOffDiagonal(int i, int j, const Eigen::Matrix<double, 7, 7>& B);
  void SetZero();
  void AddToDiagonal(double value);
  /// Adds a full symmetric n x n matrix (its upper triangle; dense storage only: offline).
  void AddDense(const Eigen::MatrixXd& A);
  double MaxAbsDiagonal() const;

  const Eigen::MatrixXd& dense() const { return dense_; }
  const Eigen::SparseMatrix<double>& sparse() const { return sparse_matrix_; }

 private:
  int num_blocks_ = 0;
  bool sparse_ = false;
  Eigen::MatrixXd dense_;
  Eigen::SparseMatrix<double> sparse_matrix_;
  /// Sparse: per block column j, the sorted block rows stored in it.
  std::vector<std::vector<int>> column_blocks_;
};

}  // namespace tangent::optimizer
