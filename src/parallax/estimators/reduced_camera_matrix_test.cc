#include "parallax/estimators/reduced_camera_matrix.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <Eigen/Cholesky>

#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// Five pose-like blocks of 6 and one intrinsics block of 3, coupled along a chain (0-1, 1-2,
// 2-3, 3-4) with the intrinsics seen with poses 1 and 4: S is sparse but connected.
ReducedMatrixStructure ChainStructure() {
  ReducedMatrixStructure structure;
  for (int block = 0; block < 5; ++block) structure.AddVariableBlock(6 * block, 6);
  structure.AddVariableBlock(30, 3);
  for (int block = 0; block < 4; ++block) structure.Couple({6 * block, 6 * (block + 1)});
  structure.Couple({30, 6, 30});  // Repeats are allowed.
  structure.Couple({24, 30});
  structure.Finalize();
  return structure;
}

TEST(ReducedMatrixStructure, StoresCoupledBlocksAndTheDiagonalOnly) {
  const ReducedMatrixStructure structure = ChainStructure();
  EXPECT_EQ(structure.NumVariables(), 33);
  EXPECT_EQ(structure.NumBlocks(), 6);
  EXPECT_EQ(structure.BlockAt(0), 0);
  EXPECT_EQ(structure.BlockAt(17), 2);
  EXPECT_EQ(structure.BlockAt(32), 5);
  // 6 diagonal + 4 chain + 2 intrinsics blocks, each once, in the lower triangle.
  EXPECT_EQ(structure.Cols().size(), 12u);
  EXPECT_GE(structure.FindBlock(1, 0), 0);
  EXPECT_EQ(structure.FindBlock(0, 1), -1);  // Upper triangle: never stored.
  EXPECT_EQ(structure.FindBlock(2, 0), -1);  // Never coupled.
  EXPECT_GE(structure.FindBlock(5, 1), 0);
  EXPECT_GE(structure.FindBlock(5, 4), 0);
  EXPECT_EQ(structure.FindBlock(5, 2), -1);
  EXPECT_EQ(structure.NumValues(), 5u * 36 + 9 + 4 * 36 + 2 * 18);
}

// Millions of repeated couplings (every point of a pair couples it again) fold into the
// distinct blocks along the way and give the same structure.
TEST(ReducedMatrixStructure, RepeatedCouplingsGiveTheSameStructure) {
  ReducedMatrixStructure structure;
  for (int block = 0; block < 5; ++block) structure.AddVariableBlock(6 * block, 6);
  structure.AddVariableBlock(30, 3);
  for (int repeat = 0; repeat < 400000; ++repeat) {
    const int block = repeat % 4;
    structure.Couple({6 * block, 6 * (block + 1)});
    if (repeat % 1000 == 0) structure.Couple({30, 6});
    if (repeat % 1000 == 500) structure.Couple({24, 30});
  }
  structure.Finalize();
  const ReducedMatrixStructure chain = ChainStructure();
  EXPECT_EQ(structure.RowBegin(), chain.RowBegin());
  EXPECT_EQ(structure.Cols(), chain.Cols());
  EXPECT_EQ(structure.ValuesBegin(), chain.ValuesBegin());
}

// A random symmetric positive definite matrix with the structure's pattern, written into both
// storages block by block as the solver writes them.
void FillBoth(const ReducedMatrixStructure& structure, DenseReducedMatrix* dense,
              BlockSparseReducedMatrix* sparse) {
  dense->SetZero();
  sparse->SetZero();
  for (int row = 0; row < structure.NumBlocks(); ++row) {
    for (int index = structure.RowBegin()[row]; index < structure.RowBegin()[row + 1]; ++index) {
      const int col = structure.Cols()[index];
      const int rows = structure.BlockSize(row);
      const int cols = structure.BlockSize(col);
      Eigen::MatrixXd block(rows, cols);
      for (int r = 0; r < rows; ++r) {
        for (int c = 0; c < cols; ++c) block(r, c) = RandomUniformReal(-1.0, 1.0);
      }
      if (row == col)
        block = block * block.transpose() + 40.0 * Eigen::MatrixXd::Identity(rows, rows);
      const int row_offset = structure.BlockOffset(row);
      const int col_offset = structure.BlockOffset(col);
      dense->Block(row_offset, col_offset, rows, cols) = block;
      sparse->Block(row_offset, col_offset, rows, cols) = block;
    }
  }
}

TEST(BlockSparseReducedMatrix, ConjugateGradientsSolveAsCholeskyDoes) {
  SetPRNGSeed(3);
  const ReducedMatrixStructure structure = ChainStructure();
  DenseReducedMatrix dense(structure);
  BlockSparseReducedMatrix sparse(structure);
  FillBoth(structure, &dense, &sparse);
  dense.AddToDiagonal(7, 2.5);
  sparse.AddToDiagonal(7, 2.5);
  EXPECT_DOUBLE_EQ(dense.Diagonal(7), sparse.Diagonal(7));
  EXPECT_DOUBLE_EQ(dense.Diagonal(31), sparse.Diagonal(31));

  Eigen::VectorXd b(structure.NumVariables());
  for (int i = 0; i < b.size(); ++i) b[i] = RandomUniformReal(-1.0, 1.0);
  ConjugateGradientOptions options;
  Eigen::VectorXd x_dense, x_sparse;
  int dense_iterations = -1, sparse_iterations = -1;
  ASSERT_TRUE(dense.Solve(b, options, &x_dense, &dense_iterations));
  ASSERT_TRUE(sparse.Solve(b, options, &x_sparse, &sparse_iterations));
  EXPECT_EQ(dense_iterations, 0);
  EXPECT_GT(sparse_iterations, 0);
  EXPECT_LE(sparse_iterations, structure.NumVariables());
  EXPECT_THAT(x_sparse, EigenMatrixNear(x_dense, 1e-7 * x_dense.norm()));

  // Sums of partial matrices agree too.
  DenseReducedMatrix dense_sum = dense;
  BlockSparseReducedMatrix sparse_sum = sparse;
  dense_sum += dense;
  sparse_sum += sparse;
  ASSERT_TRUE(dense_sum.Solve(b, options, &x_dense, &dense_iterations));
  ASSERT_TRUE(sparse_sum.Solve(b, options, &x_sparse, &sparse_iterations));
  EXPECT_THAT(x_sparse, EigenMatrixNear(x_dense, 1e-7 * x_dense.norm()));
}

TEST(BlockSparseReducedMatrix, IndefiniteDiagonalBlockFails) {
  const ReducedMatrixStructure structure = ChainStructure();
  BlockSparseReducedMatrix sparse(structure);
  sparse.SetZero();  // All-zero diagonal blocks have no Cholesky factor.
  Eigen::VectorXd x;
  int iterations = 0;
  EXPECT_FALSE(sparse.Solve(Eigen::VectorXd::Ones(structure.NumVariables()), {}, &x, &iterations));
}

TEST(BlockSparseReducedMatrix, BlockThatWasNeverCoupledIsAProgrammingError) {
  const ReducedMatrixStructure structure = ChainStructure();
  BlockSparseReducedMatrix sparse(structure);
  sparse.SetZero();
  EXPECT_THROW((sparse.Block<6, 6>(12, 0)), CheckError);
}

}  // namespace
}  // namespace parallax
