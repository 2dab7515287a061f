#include "parallax/estimators/solvers/essential_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <limits>

#include "parallax/estimators/testing/two_view_scene.h"
#include "parallax/geometry/essential_matrix.h"
#include "parallax/math/random.h"
#include "parallax/optim/ransac.h"

namespace parallax {
namespace {

using test::Head;
using test::kImageHeight;
using test::kImageWidth;
using test::ProjectiveDistance;
using test::RandomImagePoint;
using test::RandomUnitVector;
using test::TwoViewScene;

constexpr double kFocal = 1000;

// Random points seen by two cameras of focal length kFocal (1024 x 768 images), a rotation of
// up to 0.3 rad between them; the solvers take their normalised coordinates (normalized1,
// normalized2).
TwoViewScene RandomScene(int num_points) {
  test::TwoViewSceneOptions options;
  options.focal1 = options.focal2 = kFocal;
  options.min_rotation = 0.0;
  return test::RandomTwoViewScene(num_points, options);
}

TEST(EssentialMatrixFivePoint, OneSolutionIsExact) {
  for (int trial = 0; trial < 100; ++trial) {
    const TwoViewScene scene = RandomScene(5);
    const Eigen::Matrix3d E_true = EssentialFromPose(scene.cam2_from_cam1);
    std::vector<Eigen::Matrix3d> models;
    EstimateEssentialMatrixFivePoint(scene.normalized1, scene.normalized2, &models);
    ASSERT_FALSE(models.empty());
    ASSERT_LE(models.size(), 10u);
    double best = std::numeric_limits<double>::max();
    for (const Eigen::Matrix3d& E : models) {
      best = std::min(best, ProjectiveDistance(E, E_true));
      // Every candidate is an essential matrix that fits the five correspondences.
      const Eigen::Vector3d singular_values = Eigen::JacobiSVD<Eigen::Matrix3d>(E).singularValues();
      EXPECT_NEAR(singular_values(0), singular_values(1), 1e-6);
      EXPECT_LT(singular_values(2), 1e-6);
      for (int i = 0; i < 5; ++i) {
        EXPECT_LT(ComputeSquaredSampsonError(scene.normalized1[i], scene.normalized2[i], E), 1e-14);
      }
    }
    EXPECT_LT(best, 1e-8) << "trial " << trial;
  }
}

TEST(EssentialMatrixFivePoint, LeastSquaresAndPlanarScenes) {
  // More than five points: the least-squares null space still contains E.
  const TwoViewScene scene = RandomScene(30);
  std::vector<Eigen::Matrix3d> models;
  EstimateEssentialMatrixFivePoint(scene.normalized1, scene.normalized2, &models);
  double best = std::numeric_limits<double>::max();
  for (const Eigen::Matrix3d& E : models) {
    best = std::min(best, ProjectiveDistance(E, EssentialFromPose(scene.cam2_from_cam1)));
  }
  EXPECT_LT(best, 1e-8);
  // Coplanar points are not degenerate for the 5-point algorithm (Nistér 2004, sec. 1).
  TwoViewScene plane = RandomScene(0);
  plane.cam2_from_cam1 = scene.cam2_from_cam1;
  const Eigen::Vector3d normal =
      (Eigen::Vector3d(0, 0, -1) + 0.3 * RandomUnitVector()).normalized();
  while (plane.points3D.size() < 5) {
    const Eigen::Vector3d ray = plane.K1.inverse() * RandomImagePoint().homogeneous();
    plane.Add(ray * normal.dot(Eigen::Vector3d(0, 0, 6)) / normal.dot(ray));
  }
  EstimateEssentialMatrixFivePoint(plane.normalized1, plane.normalized2, &models);
  best = std::numeric_limits<double>::max();
  for (const Eigen::Matrix3d& E : models) {
    best = std::min(best, ProjectiveDistance(E, EssentialFromPose(plane.cam2_from_cam1)));
  }
  EXPECT_LT(best, 1e-8);
}

TEST(EssentialMatrixEightPoint, RecoversExactModel) {
  for (int trial = 0; trial < 20; ++trial) {
    const TwoViewScene scene = RandomScene(50);
    std::vector<Eigen::Matrix3d> models;
    for (size_t count : {size_t{8}, size_t{50}}) {
      EstimateEssentialMatrixEightPoint(Head(scene.normalized1, count),
                                        Head(scene.normalized2, count), &models);
      ASSERT_EQ(models.size(), 1u);
      EXPECT_LT(ProjectiveDistance(models[0], EssentialFromPose(scene.cam2_from_cam1)), 1e-8);
      const Eigen::Vector3d singular_values =
          Eigen::JacobiSVD<Eigen::Matrix3d>(models[0]).singularValues();
      EXPECT_NEAR(singular_values(0), singular_values(1), 1e-12);
      EXPECT_NEAR(singular_values(2), 0.0, 1e-12);
    }
  }
}

TEST(EssentialMatrix, RefusesDegenerateInput) {
  const TwoViewScene scene = RandomScene(10);
  std::vector<Eigen::Matrix3d> models = {Eigen::Matrix3d::Identity()};
  EstimateEssentialMatrixFivePoint(Head(scene.normalized1, 4), Head(scene.normalized2, 4), &models);
  EXPECT_TRUE(models.empty());
  EstimateEssentialMatrixEightPoint(Head(scene.normalized1, 7), Head(scene.normalized2, 7),
                                    &models);
  EXPECT_TRUE(models.empty());
  std::vector<Eigen::Vector2d> bad = Head(scene.normalized1, 8);
  bad[2].y() = std::numeric_limits<double>::quiet_NaN();
  EstimateEssentialMatrixFivePoint(Head(bad, 5), Head(scene.normalized2, 5), &models);
  EXPECT_TRUE(models.empty());
  EstimateEssentialMatrixFivePoint(bad, Head(scene.normalized2, 8), &models);
  EXPECT_TRUE(models.empty());
  bad[2].y() = -std::numeric_limits<double>::infinity();
  EstimateEssentialMatrixEightPoint(bad, Head(scene.normalized2, 8), &models);
  EXPECT_TRUE(models.empty());
  // The same correspondence five times, and points on one 3D line.
  const std::vector<Eigen::Vector2d> same1(5, scene.normalized1[0]), same2(5, scene.normalized2[0]);
  EstimateEssentialMatrixFivePoint(same1, same2, &models);
  EXPECT_TRUE(models.empty());
  std::vector<Eigen::Vector2d> line1, line2;
  const Eigen::Vector3d origin(0, 0, 6), direction = RandomUnitVector();
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d point = origin + RandomUniformReal(-1, 1) * direction;
    line1.push_back(point.hnormalized());
    line2.push_back((scene.cam2_from_cam1 * point).hnormalized());
  }
  EstimateEssentialMatrixFivePoint(Head(line1, 5), Head(line2, 5), &models);
  EXPECT_TRUE(models.empty());
  EstimateEssentialMatrixEightPoint(line1, line2, &models);
  EXPECT_TRUE(models.empty());
}

TEST(EssentialMatrixLoRansac, NoiseAndFortyPercentOutliers) {
  for (int trial = 0; trial < 3; ++trial) {
    TwoViewScene scene = RandomScene(1000);
    const double noise = 0.5 / kFocal;
    std::vector<char> is_inlier(scene.normalized1.size());
    for (size_t i = 0; i < scene.normalized1.size(); ++i) {
      is_inlier[i] = i % 5 >= 2;
      scene.normalized1[i] += Eigen::Vector2d(RandomGaussian(0, noise), RandomGaussian(0, noise));
      if (is_inlier[i]) {
        scene.normalized2[i] += Eigen::Vector2d(RandomGaussian(0, noise), RandomGaussian(0, noise));
      } else {
        scene.normalized2[i] =
            Eigen::Vector2d(RandomUniformReal(-0.5, 0.5) * kImageWidth / kFocal,
                            RandomUniformReal(-0.5, 0.5) * kImageHeight / kFocal);
      }
    }
    RansacOptions options;
    options.max_error = 1.5 / kFocal;  // 3 sigma of the 0.5 px noise.
    const LoRansac<EssentialMatrixFivePointEstimator, EssentialMatrixEightPointEstimator> ransac(
        options);
    const auto report = ransac.Estimate(scene.normalized1, scene.normalized2);
    ASSERT_TRUE(report.success);
    size_t inliers_kept = 0, outliers_kept = 0, num_true_inliers = 0;
    for (size_t i = 0; i < is_inlier.size(); ++i) {
      num_true_inliers += is_inlier[i];
      if (report.inlier_mask[i]) (is_inlier[i] ? inliers_kept : outliers_kept)++;
    }
    std::cerr << "kept " << inliers_kept << "/" << num_true_inliers << " inliers, " << outliers_kept
              << "/" << is_inlier.size() - num_true_inliers << " outliers\n";
    EXPECT_GE(inliers_kept, 0.95 * num_true_inliers);
    // About 1 % of uniform outliers fall within 1.5 px of their epipolar line and cannot be
    // rejected; the count is Poisson (4 expected of 400), so allow two and a half times that.
    EXPECT_LE(outliers_kept, 0.025 * (is_inlier.size() - num_true_inliers));
    // The relative pose from the model is within a fraction of a degree of the truth.
    Rigid3d estimated;
    std::vector<Eigen::Vector2d> inliers1, inliers2;
    for (size_t i = 0; i < is_inlier.size(); ++i) {
      if (report.inlier_mask[i]) {
        inliers1.push_back(scene.normalized1[i]);
        inliers2.push_back(scene.normalized2[i]);
      }
    }
    ASSERT_TRUE(PoseFromEssentialMatrix(report.model, inliers1, inliers2, &estimated));
    EXPECT_LT(RotationAngleDegrees(estimated.rotation, scene.cam2_from_cam1.rotation), 0.2);
    EXPECT_LT(
        std::acos(std::min(1.0, estimated.translation.dot(scene.cam2_from_cam1.translation))) *
            180 / M_PI,
        1.0);
  }
}

}  // namespace
}  // namespace parallax
