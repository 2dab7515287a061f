#include "parallax/util/eigen_matchers.h"

#include <gtest/gtest.h>

namespace parallax::test {
namespace {

using ::testing::Not;

struct Transform {  // The members Rigid3dNear and Sim3dNear read.
  double scale = 1;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

TEST(EigenMatchers, MatrixNearComparesEveryCoefficientAndTheShape) {
  const Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d b = a;
  b(2, 1) += 1e-7;
  EXPECT_THAT(b, EigenMatrixNear(a, 1e-6));
  EXPECT_THAT(b, Not(EigenMatrixNear(a, 1e-8)));
  EXPECT_THAT(Eigen::Vector3d(1, 2, 3), Not(EigenMatrixNear(Eigen::Vector4d(1, 2, 3, 0), 1.0)));
  // Expressions are evaluated first.
  EXPECT_THAT(2 * a, EigenMatrixNear(a + a, 0.0));
}

TEST(EigenMatchers, TransformsNearInRotationTranslationAndScale) {
  Transform expected;
  expected.translation = Eigen::Vector3d(10, 0, 0);
  Transform actual = expected;
  actual.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1e-6, Eigen::Vector3d::UnitZ()));
  EXPECT_THAT(actual, Rigid3dNear(expected, 2e-6, 0.0));
  EXPECT_THAT(actual, Not(Rigid3dNear(expected, 5e-7, 0.0)));
  actual.translation.x() += 1e-3;
  EXPECT_THAT(actual, Not(Rigid3dNear(expected, 2e-6, 1e-4)));
  // Sim3dNear: translation relative to its length (10), scale relative.
  EXPECT_THAT(actual, Sim3dNear(expected, 2e-4));
  actual.scale = 1.01;
  EXPECT_THAT(actual, Not(Sim3dNear(expected, 2e-4)));
}

}  // namespace
}  // namespace parallax::test
