#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

namespace parallax {

// The reduced camera system S of a Schur-complement bundle adjuster: a symmetric matrix over
// the variable blocks (a pose's 6 parameters, a camera's free intrinsics), of which the lower
// triangle is kept. Blocks are addressed by the offsets of their rows and columns in the
// system; diagonal blocks are written whole. Two storages with the same interface:
// DenseReducedMatrix (all n^2 entries, Cholesky) and BlockSparseReducedMatrix (only the
// blocks of variables that share a point, preconditioned conjugate gradients), so that one
// solver template builds and solves either.

// Which blocks of S can be non-zero: the variable blocks by offset, and the pairs of blocks
// (row block >= column block, by index) that some point or observation couples.
class ReducedMatrixStructure {
 public:
  // A variable block at `offset` of `size` parameters; call in increasing offset order.
  void AddVariableBlock(int offset, int size);
  // Couples the variable blocks at these offsets (any order, repeats allowed): every pair of
  // them, and each with itself. Call Finalize() after the last one.
  void Couple(std::vector<int> offsets);
  void Finalize();

  int NumVariables() const { return num_variables_; }
  int NumBlocks() const { return static_cast<int>(block_offsets_.size()); }
  int BlockOffset(int block) const { return block_offsets_[block]; }
  int BlockSize(int block) const { return block_sizes_[block]; }
  int BlockAt(int offset) const { return block_of_offset_[offset]; }
  // The stored (lower-triangle) blocks: row r's columns are cols_[row_begin_[r] ..
  // row_begin_[r + 1]), ascending, each with the start of its values in values_begin_.
  const std::vector<int>& RowBegin() const { return row_begin_; }
  const std::vector<int>& Cols() const { return cols_; }
  const std::vector<size_t>& ValuesBegin() const { return values_begin_; }
  size_t NumValues() const { return values_begin_.empty() ? 0 : values_begin_.back(); }
  // Index of stored block (row, col) in Cols(), by block index; -1 when not stored.
  int FindBlock(int row, int col) const;

 private:
  int num_variables_ = 0;
  std::vector<int> block_offsets_;
  std::vector<int> block_sizes_;
  std::vector<int> block_of_offset_;
  std::vector<uint64_t> pairs_;    // row << 32 | col, until Finalize().
  size_t num_distinct_pairs_ = 0;  // Size of pairs_ after its last deduplication.
  std::vector<int> row_begin_;
  std::vector<int> cols_;
  std::vector<size_t> values_begin_;
};

// Options of the conjugate-gradient solve of the sparse system.
struct ConjugateGradientOptions {
  int max_num_iterations = 1000;
  double relative_tolerance = 1e-8;  // Stop when |S x - b| <= this * |b|.
};

class DenseReducedMatrix {
 public:
  DenseReducedMatrix() = default;
  explicit DenseReducedMatrix(const ReducedMatrixStructure& structure)
      : n_(structure.NumVariables()) {}
  void SetZero() { matrix_.setZero(n_, n_); }
  template <int Rows, int Cols>
  auto Block(int row, int col) {
    return matrix_.block<Rows, Cols>(row, col);
  }
  auto Block(int row, int col, int rows, int cols) { return matrix_.block(row, col, rows, cols); }
  DenseReducedMatrix& operator+=(const DenseReducedMatrix& other) {
    matrix_ += other.matrix_;
    return *this;
  }
  double Diagonal(int d) const { return matrix_(d, d); }
  void AddToDiagonal(int d, double value) { matrix_(d, d) += value; }
  // Cholesky of the lower triangle; false when S is not positive definite. (Out of line: the
  // header is included widely, and a Cholesky instantiated in each includer costs each one.)
  bool Solve(const Eigen::VectorXd& b, const ConjugateGradientOptions& options, Eigen::VectorXd* x,
             int* num_iterations) const;

 private:
  int n_ = 0;
  Eigen::MatrixXd matrix_;
};

class BlockSparseReducedMatrix {
 public:
  BlockSparseReducedMatrix() = default;
  explicit BlockSparseReducedMatrix(const ReducedMatrixStructure& structure)
      : structure_(&structure) {}
  void SetZero() { values_.assign(structure_->NumValues(), 0.0); }
  template <int Rows, int Cols>
  Eigen::Map<Eigen::Matrix<double, Rows, Cols>> Block(int row, int col) {
    return Eigen::Map<Eigen::Matrix<double, Rows, Cols>>(BlockValues(row, col));
  }
  Eigen::Map<Eigen::MatrixXd> Block(int row, int col, int rows, int cols) {
    return Eigen::Map<Eigen::MatrixXd>(BlockValues(row, col), rows, cols);
  }
  BlockSparseReducedMatrix& operator+=(const BlockSparseReducedMatrix& other);
  double Diagonal(int d) const;
  void AddToDiagonal(int d, double value);
  // Conjugate gradients preconditioned by the inverses of the diagonal blocks (block
  // Jacobi); false when a diagonal block is not positive definite or the iteration breaks
  // down. Each iteration costs one pass over the stored blocks.
  bool Solve(const Eigen::VectorXd& b, const ConjugateGradientOptions& options, Eigen::VectorXd* x,
             int* num_iterations) const;

 private:
  double* BlockValues(int row_offset, int col_offset);
  size_t DiagonalIndex(int d) const;  // Of entry (d, d) in values_.
  void Multiply(const Eigen::VectorXd& x, Eigen::VectorXd* y) const;

  const ReducedMatrixStructure* structure_ = nullptr;
  std::vector<double> values_;  // Each block column-major.
};

}  // namespace parallax
