#include "parallax/estimators/reduced_camera_matrix.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "parallax/util/check.h"

namespace parallax {

void ReducedMatrixStructure::AddVariableBlock(int offset, int size) {
  PARALLAX_CHECK_EQ(offset, num_variables_);
  PARALLAX_CHECK_GT(size, 0);
  block_offsets_.push_back(offset);
  block_sizes_.push_back(size);
  block_of_offset_.insert(block_of_offset_.end(), static_cast<size_t>(size), NumBlocks() - 1);
  num_variables_ += size;
}

void ReducedMatrixStructure::Couple(std::vector<int> offsets) {
  std::sort(offsets.begin(), offsets.end());
  offsets.erase(std::unique(offsets.begin(), offsets.end()), offsets.end());
  for (size_t a = 0; a < offsets.size(); ++a) {
    const uint64_t row = static_cast<uint64_t>(BlockAt(offsets[a]));
    for (size_t b = 0; b <= a; ++b)
      pairs_.push_back(row << 32 | static_cast<uint64_t>(BlockAt(offsets[b])));
  }
  // Most pairs repeat (every point of two images couples them again): fold the repeats away
  // whenever the list has doubled, so that it stays near the number of distinct blocks.
  if (pairs_.size() >= 2 * num_distinct_pairs_ + (size_t{1} << 20)) {
    std::sort(pairs_.begin(), pairs_.end());
    pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
    num_distinct_pairs_ = pairs_.size();
  }
}

void ReducedMatrixStructure::Finalize() {
  // Every diagonal block is stored, so that damping and the preconditioner always find it.
  for (int block = 0; block < NumBlocks(); ++block) {
    pairs_.push_back(static_cast<uint64_t>(block) << 32 | static_cast<uint64_t>(block));
  }
  std::sort(pairs_.begin(), pairs_.end());
  pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
  row_begin_.assign(static_cast<size_t>(NumBlocks()) + 1, 0);
  cols_.clear();
  values_begin_.assign(1, 0);
  for (const uint64_t pair : pairs_) {
    const int row = static_cast<int>(pair >> 32);
    const int col = static_cast<int>(pair & 0xffffffffu);
    ++row_begin_[row + 1];
    cols_.push_back(col);
    values_begin_.push_back(values_begin_.back() +
                            static_cast<size_t>(block_sizes_[row] * block_sizes_[col]));
  }
  for (int row = 0; row < NumBlocks(); ++row) row_begin_[row + 1] += row_begin_[row];
  pairs_.clear();
  pairs_.shrink_to_fit();
}

int ReducedMatrixStructure::FindBlock(int row, int col) const {
  const auto begin = cols_.begin() + row_begin_[row];
  const auto end = cols_.begin() + row_begin_[row + 1];
  const auto it = std::lower_bound(begin, end, col);
  return it != end && *it == col ? static_cast<int>(it - cols_.begin()) : -1;
}

double* BlockSparseReducedMatrix::BlockValues(int row_offset, int col_offset) {
  const int index =
      structure_->FindBlock(structure_->BlockAt(row_offset), structure_->BlockAt(col_offset));
  PARALLAX_CHECK_GE(index, 0);
  return values_.data() + structure_->ValuesBegin()[index];
}

bool DenseReducedMatrix::Solve(const Eigen::VectorXd& b,
                               const ConjugateGradientOptions& /*options*/, Eigen::VectorXd* x,
                               int* num_iterations) const {
  *num_iterations = 0;
  const Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(matrix_);
  if (llt.info() != Eigen::Success) return false;
  *x = llt.solve(b);
  return true;
}

BlockSparseReducedMatrix& BlockSparseReducedMatrix::operator+=(
    const BlockSparseReducedMatrix& other) {
  PARALLAX_CHECK_EQ(values_.size(), other.values_.size());
  for (size_t i = 0; i < values_.size(); ++i) values_[i] += other.values_[i];
  return *this;
}

size_t BlockSparseReducedMatrix::DiagonalIndex(int d) const {
  const int block = structure_->BlockAt(d);
  const int local = d - structure_->BlockOffset(block);
  return structure_->ValuesBegin()[structure_->FindBlock(block, block)] +
         static_cast<size_t>(local * structure_->BlockSize(block) + local);
}

double BlockSparseReducedMatrix::Diagonal(int d) const { return values_[DiagonalIndex(d)]; }

void BlockSparseReducedMatrix::AddToDiagonal(int d, double value) {
  values_[DiagonalIndex(d)] += value;
}

// y = S x from the lower blocks: block (r, c) adds B x_c to y_r and, off the diagonal,
// B^T x_r to y_c.
void BlockSparseReducedMatrix::Multiply(const Eigen::VectorXd& x, Eigen::VectorXd* y) const {
  const ReducedMatrixStructure& s = *structure_;
  y->setZero(x.size());
  for (int row = 0; row < s.NumBlocks(); ++row) {
    const int row_offset = s.BlockOffset(row);
    const int rows = s.BlockSize(row);
    for (int index = s.RowBegin()[row]; index < s.RowBegin()[row + 1]; ++index) {
      const int col = s.Cols()[index];
      const int col_offset = s.BlockOffset(col);
      const int cols = s.BlockSize(col);
      const double* values = values_.data() + s.ValuesBegin()[index];
      if (rows == 6 && cols == 6) {  // Pose-pose: almost all blocks, at fixed size.
        const Eigen::Map<const Eigen::Matrix<double, 6, 6>> block(values);
        y->segment<6>(row_offset).noalias() += block * x.segment<6>(col_offset);
        if (col != row)
          y->segment<6>(col_offset).noalias() += block.transpose() * x.segment<6>(row_offset);
        continue;
      }
      const Eigen::Map<const Eigen::MatrixXd> block(values, rows, cols);
      y->segment(row_offset, rows).noalias() += block * x.segment(col_offset, cols);
      if (col != row)
        y->segment(col_offset, cols).noalias() += block.transpose() * x.segment(row_offset, rows);
    }
  }
}

bool BlockSparseReducedMatrix::Solve(const Eigen::VectorXd& b,
                                     const ConjugateGradientOptions& options, Eigen::VectorXd* x,
                                     int* num_iterations) const {
  const ReducedMatrixStructure& s = *structure_;
  *num_iterations = 0;
  // Block-Jacobi preconditioner: the inverse of each diagonal block.
  std::vector<Eigen::MatrixXd> preconditioner(static_cast<size_t>(s.NumBlocks()));
  for (int block = 0; block < s.NumBlocks(); ++block) {
    const int size = s.BlockSize(block);
    const Eigen::Map<const Eigen::MatrixXd> diagonal(
        values_.data() + s.ValuesBegin()[s.FindBlock(block, block)], size, size);
    const Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(diagonal);
    if (llt.info() != Eigen::Success) return false;
    preconditioner[block] = llt.solve(Eigen::MatrixXd::Identity(size, size));
  }
  const auto precondition = [&](const Eigen::VectorXd& r, Eigen::VectorXd* z) {
    z->resize(r.size());
    for (int block = 0; block < s.NumBlocks(); ++block) {
      const int offset = s.BlockOffset(block);
      const int size = s.BlockSize(block);
      z->segment(offset, size).noalias() = preconditioner[block] * r.segment(offset, size);
    }
  };

  x->setZero(b.size());
  const double b_norm = b.norm();
  if (b_norm == 0) return true;
  Eigen::VectorXd r = b, z, p, q;
  precondition(r, &z);
  p = z;
  double rz = r.dot(z);
  for (int iteration = 0; iteration < options.max_num_iterations; ++iteration) {
    Multiply(p, &q);
    const double pq = p.dot(q);
    if (!(pq > 0)) return iteration > 0;  // Not positive definite along p: keep what we have.
    const double alpha = rz / pq;
    x->noalias() += alpha * p;
    r.noalias() -= alpha * q;
    *num_iterations = iteration + 1;
    if (r.norm() <= options.relative_tolerance * b_norm) break;
    precondition(r, &z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return x->allFinite();
}

}  // namespace parallax
