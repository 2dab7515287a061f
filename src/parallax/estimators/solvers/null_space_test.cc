#include "parallax/estimators/solvers/null_space.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <limits>

namespace parallax {
namespace {

constexpr double kMinPivotRatio = 1e-10;

template <int kRows, int kCols>
Eigen::Matrix<double, kRows, kCols> RandomMatrix() {
  return Eigen::Matrix<double, kRows, kCols>::Random();
}

// Elimination finds a basis of A's null space: A N = 0 and N has full column rank.
template <int kRows, int kCols>
void ExpectEliminationFindsNullSpace(const Eigen::Matrix<double, kRows, kCols>& A) {
  Eigen::Matrix<double, kCols, kCols - kRows> null_space;
  ASSERT_TRUE(NullSpaceByElimination(A, &null_space, kMinPivotRatio));
  EXPECT_LT((A * null_space).norm(), 1e-12 * A.norm() * null_space.norm());
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(null_space);
  EXPECT_GT(svd.singularValues().minCoeff(), 1e-6 * svd.singularValues().maxCoeff());
}

TEST(NullSpaceTest, SpansTheNullSpaceOfRandomSystems) {
  std::srand(7);
  for (int trial = 0; trial < 100; ++trial) {
    ExpectEliminationFindsNullSpace(RandomMatrix<7, 9>());  // The 7-point F's system.
    ExpectEliminationFindsNullSpace(RandomMatrix<8, 9>());  // The 4-point H's.
  }
}

TEST(NullSpaceTest, PivotsOnColumnsWhenLeadingColumnsAreDependent) {
  std::srand(11);
  Eigen::Matrix<double, 7, 9> A = RandomMatrix<7, 9>();
  // Full rank, but the first seven columns span only five dimensions (one is zero, one a
  // combination of two others): the pivots must come from the last two.
  A.col(3) = 2.0 * A.col(1) - A.col(5);
  A.col(0).setZero();
  ExpectEliminationFindsNullSpace(A);
}

TEST(NullSpaceTest, RankDeficientAndNonFiniteSystemsAreRefused) {
  std::srand(13);
  Eigen::Matrix<double, 7, 9> A = RandomMatrix<7, 9>();
  A.row(6) = A.row(0) + 3.0 * A.row(2);  // Rank 6: a three-dimensional null space.
  Eigen::Matrix<double, 9, 2> null_space;
  EXPECT_FALSE(NullSpaceByElimination(A, &null_space, kMinPivotRatio));

  const Eigen::Matrix<double, 7, 9> zero = Eigen::Matrix<double, 7, 9>::Zero();
  EXPECT_FALSE(NullSpaceByElimination(zero, &null_space, kMinPivotRatio));

  Eigen::Matrix<double, 7, 9> with_nan = RandomMatrix<7, 9>();
  with_nan(4, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(NullSpaceByElimination(with_nan, &null_space, kMinPivotRatio));
}

}  // namespace
}  // namespace parallax
