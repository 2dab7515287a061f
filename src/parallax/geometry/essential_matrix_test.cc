#include "parallax/geometry/essential_matrix.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"

namespace parallax {
namespace {

using test::CalibrationMatrix;
using test::EigenMatrixNear;
using test::ProjectiveDistance;
using test::RandomUnitVector;

// A relative pose with a rotation of up to ~0.5 rad and a unit baseline.
Rigid3d RandomRelativePose() { return test::RandomRelativePose(0.05, 0.5); }

// Points in front of both cameras (cam1 frame, depths 3..8).
std::vector<Eigen::Vector3d> RandomPointsInFront(const Rigid3d& cam2_from_cam1, int count) {
  std::vector<Eigen::Vector3d> points;
  while (static_cast<int>(points.size()) < count) {
    const Eigen::Vector3d point(RandomUniformReal(-2, 2), RandomUniformReal(-2, 2),
                                RandomUniformReal(3, 8));
    if ((cam2_from_cam1 * point).z() > 0.5) points.push_back(point);
  }
  return points;
}

TEST(EssentialMatrix, FromPoseSatisfiesEpipolarConstraint) {
  for (int trial = 0; trial < 10; ++trial) {
    const Rigid3d cam2_from_cam1 = RandomRelativePose();
    const Eigen::Matrix3d E = EssentialFromPose(cam2_from_cam1);
    for (const Eigen::Vector3d& point : RandomPointsInFront(cam2_from_cam1, 20)) {
      const Eigen::Vector3d x1 = point / point.z();
      const Eigen::Vector3d x2_unnormalized = cam2_from_cam1 * point;
      const Eigen::Vector3d x2 = x2_unnormalized / x2_unnormalized.z();
      EXPECT_NEAR(x2.dot(E * x1), 0.0, 1e-12);
    }
    // An essential matrix has two equal singular values and a zero one.
    const Eigen::Vector3d singular_values = Eigen::JacobiSVD<Eigen::Matrix3d>(E).singularValues();
    EXPECT_NEAR(singular_values(0), singular_values(1), 1e-12);
    EXPECT_NEAR(singular_values(2), 0.0, 1e-12);
  }
}

TEST(EssentialMatrix, FundamentalRoundTrip) {
  const Eigen::Matrix3d K1 = CalibrationMatrix(800, 320, 240);
  const Eigen::Matrix3d K2 = CalibrationMatrix(1200, 500, 400);
  const Rigid3d cam2_from_cam1 = RandomRelativePose();
  const Eigen::Matrix3d E = EssentialFromPose(cam2_from_cam1);
  const Eigen::Matrix3d F = FundamentalFromEssential(E, K1, K2);
  EXPECT_LT(ProjectiveDistance(EssentialFromFundamental(F, K1, K2), E), 1e-12);
  // F relates pixels: x2_px^T F x1_px = 0.
  for (const Eigen::Vector3d& point : RandomPointsInFront(cam2_from_cam1, 10)) {
    const Eigen::Vector3d x1 = K1 * point / point.z();
    const Eigen::Vector3d in_cam2 = cam2_from_cam1 * point;
    const Eigen::Vector3d x2 = K2 * in_cam2 / in_cam2.z();
    EXPECT_NEAR(x2.dot(F * x1) / (F.norm() * x1.norm() * x2.norm()), 0.0, 1e-14);
  }
}

TEST(EssentialMatrix, DecompositionContainsTruePose) {
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3d cam2_from_cam1 = RandomRelativePose();
    const Eigen::Matrix3d R_true = cam2_from_cam1.rotation.toRotationMatrix();
    const Eigen::Vector3d t_true = cam2_from_cam1.translation.normalized();
    // Any scale and sign of E.
    const Eigen::Matrix3d E = RandomUniformReal(-3, 3) * EssentialFromPose(cam2_from_cam1);
    Eigen::Matrix3d R1, R2;
    Eigen::Vector3d t;
    DecomposeEssentialMatrix(E, &R1, &R2, &t);
    EXPECT_NEAR(R1.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(R2.determinant(), 1.0, 1e-12);
    EXPECT_THAT(R1.transpose() * R1, EigenMatrixNear(Eigen::Matrix3d::Identity(), 1e-12));
    EXPECT_NEAR(t.norm(), 1.0, 1e-12);
    EXPECT_LT(std::min((R1 - R_true).norm(), (R2 - R_true).norm()), 1e-10);
    EXPECT_LT(std::min((t - t_true).norm(), (t + t_true).norm()), 1e-10);
  }
}

TEST(EssentialMatrix, PoseFromEssentialMatrixRecoversExactPose) {
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3d cam2_from_cam1 = RandomRelativePose();
    const std::vector<Eigen::Vector3d> points = RandomPointsInFront(cam2_from_cam1, 50);
    std::vector<Eigen::Vector2d> points1, points2;
    for (const Eigen::Vector3d& point : points) {
      points1.push_back(point.hnormalized());
      points2.push_back((cam2_from_cam1 * point).hnormalized());
    }
    const Eigen::Matrix3d E = -2.0 * EssentialFromPose(cam2_from_cam1);
    Rigid3d estimated;
    std::vector<Eigen::Vector3d> points3D;
    ASSERT_TRUE(PoseFromEssentialMatrix(E, points1, points2, &estimated, &points3D));
    EXPECT_LT(
        (estimated.rotation.toRotationMatrix() - cam2_from_cam1.rotation.toRotationMatrix()).norm(),
        1e-8);
    EXPECT_THAT(estimated.translation,
                EigenMatrixNear(cam2_from_cam1.translation.normalized(), 1e-8));
    // Every point passes cheirality and comes back at the unit-baseline scale.
    ASSERT_EQ(points3D.size(), points.size());
    const double scale = 1.0 / cam2_from_cam1.translation.norm();
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_THAT(points3D[i], EigenMatrixNear(scale * points[i], 1e-8 * scale * points[i].norm()));
    }
  }
}

TEST(EssentialMatrix, PoseFromEssentialMatrixRefusesBadInput) {
  Rigid3d pose;
  const std::vector<Eigen::Vector2d> points = {Eigen::Vector2d(0.1, 0.2)};
  EXPECT_FALSE(PoseFromEssentialMatrix(Eigen::Matrix3d::Identity(), {}, {}, &pose));
  EXPECT_FALSE(PoseFromEssentialMatrix(Eigen::Matrix3d::Identity(), points, {}, &pose));
  Eigen::Matrix3d nan_E = Eigen::Matrix3d::Identity();
  nan_E(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(PoseFromEssentialMatrix(nan_E, points, points, &pose));
  const std::vector<Eigen::Vector2d> nan_points = {
      Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), 0)};
  EXPECT_FALSE(PoseFromEssentialMatrix(EssentialFromPose(RandomRelativePose()), nan_points,
                                       nan_points, &pose));
}

}  // namespace
}  // namespace parallax
