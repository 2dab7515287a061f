#include "parallax/math/dense_decompositions.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

namespace parallax {

void RightSingularSystem(const Eigen::MatrixXd& A, Eigen::VectorXd* singular_values,
                         Eigen::MatrixXd* V) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  *singular_values = svd.singularValues();
  *V = svd.matrixV();
}

bool SymmetricEigenSystem(const Eigen::MatrixXd& S, Eigen::VectorXd* eigenvalues,
                          Eigen::MatrixXd* eigenvectors) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(S);
  if (solver.info() != Eigen::Success) return false;
  *eigenvalues = solver.eigenvalues();
  *eigenvectors = solver.eigenvectors();
  return true;
}

Eigen::VectorXd SolveLeastSquares(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  return A.colPivHouseholderQr().solve(b);
}

}  // namespace parallax
