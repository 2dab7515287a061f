#include "parallax/geometry/epipolar.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>

#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// The fundamental matrix of a rectified stereo pair (pure x translation, identity K): the
// epipolar lines are the rows, x2^T F x1 = y1 - y2 up to sign.
Eigen::Matrix3d RectifiedStereoF() {
  Eigen::Matrix3d F;
  F << 0, 0, 0, 0, 0, -1, 0, 1, 0;
  return F;
}

constexpr double kMax = std::numeric_limits<double>::max();

TEST(SampsonError, ZeroOnExactCorrespondences) {
  const Eigen::Matrix3d F = RectifiedStereoF();
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d point1(RandomUniformReal(-100, 100), RandomUniformReal(-100, 100));
    const Eigen::Vector2d point2(RandomUniformReal(-100, 100), point1.y());
    EXPECT_EQ(ComputeSquaredSampsonError(point1, point2, F), 0.0);
  }
}

TEST(SampsonError, RectifiedStereoIsHalfSquaredRowOffset) {
  // With e = y1 - y2 and a gradient of norm sqrt(2), Sampson = e^2 / 2: the squared distance in
  // R^4 from (x1, x2) to the closest correspondence (both points moved by e/2).
  const Eigen::Matrix3d F = 3.0 * RectifiedStereoF();
  EXPECT_NEAR(ComputeSquaredSampsonError({10, 5}, {-40, 8}, F), 4.5, 1e-12);
  EXPECT_NEAR(ComputeSquaredSampsonError({0, 0}, {7, -2}, F), 2.0, 1e-12);
}

TEST(SampsonError, VectorMatchesScalarAndHandlesDegenerateModels) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Random();
  std::vector<Eigen::Vector2d> points1, points2;
  for (int i = 0; i < 10; ++i) {
    points1.push_back(Eigen::Vector2d::Random());
    points2.push_back(Eigen::Vector2d::Random());
  }
  std::vector<double> errors;
  ComputeSquaredSampsonError(points1, points2, F, &errors);
  ASSERT_EQ(errors.size(), 10u);
  for (size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(errors[i], ComputeSquaredSampsonError(points1[i], points2[i], F));
  }
  EXPECT_EQ(ComputeSquaredSampsonError({1, 2}, {3, 4}, Eigen::Matrix3d::Zero()), kMax);
  EXPECT_EQ(ComputeSquaredSampsonError({std::numeric_limits<double>::quiet_NaN(), 2}, {3, 4}, F),
            kMax);
  EXPECT_THROW(ComputeSquaredSampsonError(points1, {}, F, &errors), CheckError);
}

TEST(HomographyError, TransferAndSymmetricTransfer) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  H(0, 0) = 2.0;  // x2 = (2 x1 + 1, y1 + 2)
  H(0, 2) = 1.0;
  H(1, 2) = 2.0;
  const std::vector<Eigen::Vector2d> points1 = {{1, 1}, {0, 0}};
  const std::vector<Eigen::Vector2d> points2 = {{3, 3}, {1, 4}};
  EXPECT_EQ(ComputeSquaredHomographyError(points1[0], points2[0], H), 0.0);
  // H x1 = (1, 2) vs (1, 4): forward 4; H^-1 x2 = (0, 2) vs (0, 0): backward 4.
  EXPECT_NEAR(ComputeSquaredHomographyError(points1[1], points2[1], H), 4.0, 1e-12);
  std::vector<double> errors;
  ComputeSquaredHomographyError(points1, points2, 5.0 * H, &errors);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NEAR(errors[0], 0.0, 1e-12);
  EXPECT_NEAR(errors[1], 4.0, 1e-12);
  ComputeSquaredSymmetricTransferError(points1, points2, -H, &errors);
  EXPECT_NEAR(errors[0], 0.0, 1e-12);
  EXPECT_NEAR(errors[1], 8.0, 1e-12);
  // Mapped to infinity, or by a singular H: the largest error.
  Eigen::Matrix3d to_infinity = Eigen::Matrix3d::Identity();
  to_infinity(2, 0) = 1.0;
  to_infinity(2, 2) = 0.0;
  EXPECT_EQ(ComputeSquaredHomographyError({0, 5}, {0, 0}, to_infinity), kMax);
  ComputeSquaredSymmetricTransferError(points1, points2, Eigen::Matrix3d::Zero(), &errors);
  EXPECT_EQ(errors[0], kMax);
  EXPECT_EQ(errors[1], kMax);
}

}  // namespace
}  // namespace parallax
