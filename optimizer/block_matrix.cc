#include "optimizer/block_matrix.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "base/check.h"

namespace tangent::optimizer {

BlockMatrix::BlockMatrix(int num_blocks, const std::vector<std::pair<int, int>>& pairs, bool sparse)
    : num_blocks_(num_blocks), sparse_(sparse) {
  const int n = 7 * num_blocks;
  if (!sparse_) {
    dense_.setZero(n, n);
    return;
  }
  column_blocks_.assign(static_cast<size_t>(num_blocks), {});
  for (int j = 0; j < num_blocks; ++j) column_blocks_[static_cast<size_t>(j)].push_back(j);
  for (const auto& [i, j] : pairs) {
    if (i < 0 || j < 0 || i >= num_blocks || j >= num_blocks) {
      throw std::invalid_argument("block matrix: block pair (" + std::to_string(i) + ", " +
                                  std::to_string(j) + ") outside " + std::to_string(num_blocks));
    }
    column_blocks_[static_cast<size_t>(j)].push_back(i);
    column_blocks_[static_cast<size_t>(i)].push_back(j);
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < num_blocks; ++j) {
    auto& rows = column_blocks_[static_cast<size_t>(j)];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (int i : rows) {
      for (int c = 0; c < 7; ++c) {
        for (int r = 0; r < 7; ++r) entries.emplace_back(7 * i + r, 7 * j + c, 0.0);
      }
    }
  }
  sparse_matrix_.resize(n, n);
  sparse_matrix_.setFromTriplets(entries.begin(), entries.end());
  sparse_matrix_.makeCompressed();
}

BlockMatrix::BlockRef BlockMatrix::Block(int i, int j) {
  if (!sparse_) {
    return BlockRef(dense_.data() + 7 * j * dense_.rows() + 7 * i,
                    Eigen::OuterStride<>(dense_.rows()));
  }
  // Every column of block column j holds the same blocks, in the same order: the block is 7
  // consecutive values per column, columns 7 x (blocks in the column) apart.
  const auto& rows = column_blocks_[static_cast<size_t>(j)];
  const auto it = std::lower_bound(rows.begin(), rows.end(), i);
  const int pos = static_cast<int>(it - rows.begin());
  double* start = sparse_matrix_.valuePtr() + sparse_matrix_.outerIndexPtr()[7 * j] + 7 * pos;
  return BlockRef(start, Eigen::OuterStride<>(7 * static_cast<int>(rows.size())));
}

void BlockMatrix::AddOffDiagonal(int i, int j, const Eigen::Matrix<double, 7, 7>& B) {
  if (i < j) {
    Block(i, j) += B;
  } else if (i > j) {
    Block(j, i) += B.transpose();
  } else {
    Block(i, i) += B + B.transpose();
  }
}

void BlockMatrix::SetZero() {
  if (sparse_) {
    std::fill_n(sparse_matrix_.valuePtr(), sparse_matrix_.nonZeros(), 0.0);
  } else {
    dense_.setZero();
  }
}

void BlockMatrix::AddToDiagonal(double value) {
  if (!sparse_) {
    dense_.diagonal().array() += value;
    return;
  }
  for (int j = 0; j < num_blocks_; ++j) Block(j, j).diagonal().array() += value;
}

void BlockMatrix::AddDense(const Eigen::MatrixXd& A) {
  TANGENT_CHECK(!sparse_ && A.rows() == dense_.rows() && A.cols() == dense_.cols());
  dense_.triangularView<Eigen::Upper>() += A;
}

double BlockMatrix::MaxAbsDiagonal() const {
  if (!sparse_) return dense_.diagonal().cwiseAbs().maxCoeff();
  double m = 0.0;
  for (int j = 0; j < num_blocks_; ++j) {
    const auto& rows = column_blocks_[static_cast<size_t>(j)];
    const int pos = static_cast<int>(std::lower_bound(rows.begin(), rows.end(), j) - rows.begin());
    for (int c = 0; c < 7; ++c) {
      const double* col = sparse_matrix_.valuePtr() + sparse_matrix_.outerIndexPtr()[7 * j + c];
      m = std::max(m, std::abs(col[7 * pos + c]));
    }
  }
  return m;
}

}  // namespace tangent::optimizer
