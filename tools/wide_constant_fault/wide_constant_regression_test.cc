// Regression test of the GCC 12 fault that failed HomographyError.TransferAndSymmetricTransfer on
// AVX-512 machines (issue 23, docs/portable-build.md): the reproducer is compiled with
// -march=x86-64-v4 and the build's own flags, so it passes only while the workaround in
// cmake/ParallaxArch.cmake protects AVX-512 code. It runs where the CPU has AVX-512.
#include <gtest/gtest.h>

#include "wide_constant_reproducer.h"

namespace parallax {
namespace {

class WideConstantRegression : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!CpuHasX86_64_V4()) GTEST_SKIP() << "the CPU has no AVX-512: x86-64-v4 code cannot run";
  }
};

TEST_F(WideConstantRegression, ThirtyTwoByteConstantKeepsItsZeroHalf) {
  const std::vector<Eigen::Vector2d> points = TwoPointsFromConstants();
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0], Eigen::Vector2d(1, 1));
  EXPECT_EQ(points[1], Eigen::Vector2d(0, 0));
}

TEST_F(WideConstantRegression, SixtyFourByteConstantKeepsItsZeroWords) {
  const std::vector<Eigen::Vector2d> points = FourPointsFromConstants();
  ASSERT_EQ(points.size(), 4u);
  EXPECT_EQ(points[0], Eigen::Vector2d(1, 1));
  for (size_t i = 1; i < points.size(); ++i) EXPECT_EQ(points[i], Eigen::Vector2d(0, 0)) << i;
}

TEST_F(WideConstantRegression, VectorsOfFourKeepTheirZeroWords) {
  const std::vector<Eigen::Vector4d> vectors = TwoVectorsFromConstants();
  ASSERT_EQ(vectors.size(), 2u);
  EXPECT_EQ(vectors[0], Eigen::Vector4d(2, 2, 0, 0));
  EXPECT_EQ(vectors[1], Eigen::Vector4d(0, 0, 0, 0));
}

}  // namespace
}  // namespace parallax
