#pragma once

#include <Eigen/Core>

namespace parallax {

// The dynamic-size dense decompositions of the small solvers (epipolar, homography and
// resection systems, EPnP) and of the report, compiled once here. Each Eigen decomposition a
// file instantiates adds its blocked Householder and matrix-product kernels to that file's
// compile time (docs/building.md, "Compile time"); five solvers each had their own copy.

// Singular values of A in descending order and its full right singular basis V (columns),
// from a two-sided Jacobi SVD. Any shape of A; V is cols x cols, so with fewer rows than
// columns its last columns span the null space.
void RightSingularSystem(const Eigen::MatrixXd& A, Eigen::VectorXd* singular_values,
                         Eigen::MatrixXd* V);

// Eigenvalues in ascending order and unit eigenvectors (columns) of the symmetric matrix S,
// of which only the lower triangle is read. False when the iteration does not converge.
bool SymmetricEigenSystem(const Eigen::MatrixXd& S, Eigen::VectorXd* eigenvalues,
                          Eigen::MatrixXd* eigenvectors);

// Least-squares solution of A x = b by Householder QR with column pivoting (rank-revealing,
// so a rank-deficient A gives a finite answer).
Eigen::VectorXd SolveLeastSquares(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);

}  // namespace parallax
