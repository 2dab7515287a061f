#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <utility>

namespace parallax {

// The null space of a full-rank kRows x kCols system (kRows < kCols) by Gauss-Jordan
// elimination with full pivoting: the minimal solvers' systems are tiny and well scaled after
// Hartley normalisation, where this is several times faster than a QR decomposition and as
// accurate. Writes a basis (not orthonormal: each vector has a 1 at one free unknown) and
// returns false when a pivot falls below `min_pivot_ratio` times the first one, i.e. the rank
// is below kRows (a degenerate sample).
template <int kRows, int kCols>
bool NullSpaceByElimination(const Eigen::Matrix<double, kRows, kCols>& A,
                            Eigen::Matrix<double, kCols, kCols - kRows>* null_space,
                            double min_pivot_ratio) {
  static_assert(kRows < kCols);
  // A NaN could otherwise sit in a free column, which is never a pivot.
  if (!A.allFinite()) return false;
  // Plain arrays: rows are swapped by index, columns through `columns`.
  double M[kRows][kCols];
  for (int i = 0; i < kRows; ++i) {
    for (int j = 0; j < kCols; ++j) M[i][j] = A(i, j);
  }
  int rows[kRows];
  for (int i = 0; i < kRows; ++i) rows[i] = i;
  int columns[kCols];
  for (int j = 0; j < kCols; ++j) columns[j] = j;
  double first_pivot = 0.0;
  for (int k = 0; k < kRows; ++k) {
    int pivot_i = k, pivot_j = k;
    double pivot_abs = -1.0;
    for (int i = k; i < kRows; ++i) {
      const double* row = M[rows[i]];
      for (int j = k; j < kCols; ++j) {
        const double value = std::abs(row[columns[j]]);
        if (value > pivot_abs) {
          pivot_abs = value;
          pivot_i = i;
          pivot_j = j;
        }
      }
    }
    if (k == 0) first_pivot = pivot_abs;
    // Also false for NaN entries, which compare false.
    if (!(pivot_abs > min_pivot_ratio * first_pivot) || !(first_pivot > 0.0) ||
        !std::isfinite(pivot_abs)) {
      return false;
    }
    std::swap(rows[k], rows[pivot_i]);
    std::swap(columns[k], columns[pivot_j]);
    double* pivot_row = M[rows[k]];
    const double inverse_pivot = 1.0 / pivot_row[columns[k]];
    // A copy the compiler knows no other row aliases, so that the updates below vectorise:
    // through `pivot_row` they were scalar, and most of the 7-point solver's time.
    double pivot[kCols];
    for (int j = 0; j < kCols; ++j) pivot[j] = pivot_row[j] *= inverse_pivot;
    for (int i = 0; i < kRows; ++i) {
      if (i == k) continue;
      double* row = M[rows[i]];
      const double factor = row[columns[k]];
      for (int j = 0; j < kCols; ++j) row[j] -= factor * pivot[j];
    }
  }
  // Reduced to [I | R] in permuted unknowns: unknown columns[k] (k < kRows) equals
  // -sum_f R(k, f) free_f, with free_f = unknown columns[kRows + f].
  null_space->setZero();
  for (int f = 0; f < kCols - kRows; ++f) {
    (*null_space)(columns[kRows + f], f) = 1.0;
    for (int k = 0; k < kRows; ++k) {
      (*null_space)(columns[k], f) = -M[rows[k]][columns[kRows + f]];
    }
  }
  return true;
}

// A^T A of an N x 9 system (column-major, so each entry is one contiguous dot product): as fast
// as a matrix product at the solvers' sizes without instantiating Eigen's blocked product
// kernels, which are slow to compile (docs/building.md, "Compile time").
inline Eigen::Matrix<double, 9, 9> NormalMatrix(const Eigen::Matrix<double, Eigen::Dynamic, 9>& A) {
  Eigen::Matrix<double, 9, 9> normal;
  for (int j = 0; j < 9; ++j) {
    for (int i = j; i < 9; ++i) normal(i, j) = normal(j, i) = A.col(i).dot(A.col(j));
  }
  return normal;
}

// Least squares with many rows (the local optimisation's refits on hundreds of inliers): the
// kNumNull eigenvectors of the smallest eigenvalues of the normal matrix A^T A (9 x 9,
// accumulated by the caller) instead of an SVD of the N x 9 system, several times cheaper.
// Squaring the condition number costs nothing measurable on Hartley-normalised rows. False
// when eigenvalue kNumNull is at most `min_eigenvalue_ratio` times the largest (rank below
// 9 - kNumNull; rounding leaves ~1e-16 of the largest in a true null direction).
template <int kNumNull>
bool NullSpaceFromNormalMatrix(const Eigen::Matrix<double, 9, 9>& normal,
                               Eigen::Matrix<double, 9, kNumNull>* null_space,
                               double min_eigenvalue_ratio) {
  if (!normal.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> solver(normal);
  if (solver.info() != Eigen::Success) return false;
  const auto& eigenvalues = solver.eigenvalues();  // Ascending.
  if (!(eigenvalues(kNumNull) > min_eigenvalue_ratio * eigenvalues(8))) return false;
  *null_space = solver.eigenvectors().template leftCols<kNumNull>();
  return true;
}

}  // namespace parallax
