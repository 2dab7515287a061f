#include "parallax/geometry/rigid3.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include "parallax/geometry/sim3.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

Rigid3d RandomRigid(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized())), t);
}

TEST(Rigid3d, ComposeAndInverse) {
  const Rigid3d b_from_a = RandomRigid(0.3, {1, 2, 3}, {1, -2, 0.5});
  const Rigid3d c_from_b = RandomRigid(-1.1, {0, 1, -1}, {0.2, 0.1, 4});
  const Eigen::Vector3d x_a(0.7, -0.4, 2.0);
  const Rigid3d c_from_a = c_from_b * b_from_a;
  EXPECT_THAT(c_from_a * x_a, EigenMatrixNear(c_from_b * (b_from_a * x_a), 1e-12));
  EXPECT_THAT(b_from_a.Inverse() * (b_from_a * x_a), EigenMatrixNear(x_a, 1e-12));
  const Matrix3x4d matrix = c_from_a.ToMatrix();
  EXPECT_THAT(matrix * x_a.homogeneous(), EigenMatrixNear(c_from_a * x_a, 1e-12));
}

TEST(Rigid3d, ProjectionCenterMapsToOrigin) {
  const Rigid3d cam_from_world = RandomRigid(0.8, {1, 0, 1}, {3, 2, 1});
  EXPECT_LT((cam_from_world * ProjectionCenter(cam_from_world)).norm(), 1e-12);
}

TEST(Rigid3d, RotationAngle) {
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond b(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(RotationAngleDegrees(a, b), 0.3 * 180 / M_PI, 1e-9);
}

TEST(Sim3d, TransformCameraPoseKeepsProjections) {
  const Sim3d b_from_a(
      2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized())),
      Eigen::Vector3d(1, 2, 3));
  const Rigid3d cam_from_a = RandomRigid(0.2, {0, 0, 1}, {0.1, 0.2, 5});
  const Rigid3d cam_from_b = TransformCameraPose(b_from_a, cam_from_a);
  const Eigen::Vector3d x_a(0.3, 0.1, 1.0);
  const Eigen::Vector3d in_cam_a = cam_from_a * x_a;
  const Eigen::Vector3d in_cam_b = cam_from_b * (b_from_a * x_a);
  EXPECT_THAT(in_cam_a.hnormalized(), EigenMatrixNear(in_cam_b.hnormalized(), 1e-12));
  EXPECT_THAT((b_from_a.Inverse() * (b_from_a * x_a)), EigenMatrixNear(x_a, 1e-12));
}

}  // namespace
}  // namespace parallax
