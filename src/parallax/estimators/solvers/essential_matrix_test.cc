#include "parallax/estimators/solvers/essential_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <limits>

#include "parallax/estimators/testing/two_view_scene.h"
#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/testing/random_geometry.h"
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

// Two 360-degree cameras among points in every direction (half of them behind either
// image plane): the unit rays of each point in both cameras.
struct RayScene {
  Rigid3d cam2_from_cam1;
  std::vector<Eigen::Vector3d> rays1, rays2;
};

RayScene RandomRayScene(int num_points) {
  RayScene scene;
  scene.cam2_from_cam1 = test::RandomRelativePose(0.0, M_PI);
  while (static_cast<int>(scene.rays1.size()) < num_points) {
    const Eigen::Vector3d point = RandomUniformReal(2.0, 10.0) * RandomUnitVector();
    const Eigen::Vector3d in_cam2 = scene.cam2_from_cam1 * point;
    if (in_cam2.norm() < 1.0) continue;
    scene.rays1.push_back(point.normalized());
    scene.rays2.push_back(in_cam2.normalized());
  }
  return scene;
}

TEST(EssentialMatrixFromRays, FiveAndEightPointsAreExactInEveryDirection) {
  SetPRNGSeed(21);
  int num_behind = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const RayScene scene = RandomRayScene(5);
    for (const Eigen::Vector3d& ray : scene.rays1) num_behind += ray.z() < 0;
    const Eigen::Matrix3d E_true = EssentialFromPose(scene.cam2_from_cam1);
    std::vector<Eigen::Matrix3d> models;
    EstimateEssentialMatrixFivePointFromRays(scene.rays1, scene.rays2, &models);
    ASSERT_FALSE(models.empty()) << "trial " << trial;
    double best = std::numeric_limits<double>::max();
    for (const Eigen::Matrix3d& E : models) {
      best = std::min(best, ProjectiveDistance(E, E_true));
      for (int i = 0; i < 5; ++i) {
        EXPECT_LT(ComputeSquaredSphericalSampsonError(scene.rays1[i], scene.rays2[i], E), 1e-16);
      }
    }
    EXPECT_LT(best, 1e-8) << "trial " << trial;
  }
  EXPECT_GT(num_behind, 150);  // Of 500 rays: the sphere, not a hemisphere.
  const RayScene scene = RandomRayScene(50);
  std::vector<Eigen::Matrix3d> models;
  EstimateEssentialMatrixEightPointFromRays(scene.rays1, scene.rays2, &models);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_LT(ProjectiveDistance(models[0], EssentialFromPose(scene.cam2_from_cam1)), 1e-10);
  // Fewer than eight rays give nothing.
  const std::vector<Eigen::Vector3d> seven1(scene.rays1.begin(), scene.rays1.begin() + 7);
  const std::vector<Eigen::Vector3d> seven2(scene.rays2.begin(), scene.rays2.begin() + 7);
  EstimateEssentialMatrixEightPointFromRays(seven1, seven2, &models);
  EXPECT_TRUE(models.empty());
}

// The spherical Sampson error is, to first order, the angle by which the rays miss a common
// epipolar plane: turn one ray out of its plane by 1 milliradian and it reads that angle,
// shared with the other ray by the ratio of their gradients.
TEST(EssentialMatrixFromRays, SphericalSampsonErrorIsTheAngleOffTheEpipolarPlane) {
  SetPRNGSeed(22);
  for (int trial = 0; trial < 50; ++trial) {
    const RayScene scene = RandomRayScene(1);
    const Eigen::Matrix3d E = EssentialFromPose(scene.cam2_from_cam1);
    const Eigen::Vector3d& ray1 = scene.rays1[0];
    const Eigen::Vector3d& ray2 = scene.rays2[0];
    EXPECT_LT(ComputeSquaredSphericalSampsonError(ray1, ray2, E), 1e-20);
    // The epipolar plane in view 2 has normal E ray1; tilt ray2 towards it.
    const Eigen::Vector3d normal = (E * ray1).normalized();
    const double angle = 1e-3;
    const Eigen::Vector3d moved = (std::cos(angle) * ray2 + std::sin(angle) * normal).normalized();
    // Only ray 2 moved: the residual grows by angle |E ray1| and the Sampson error shares it
    // between the two rays' gradients (E ray1 and E^T ray2, both tangent at the true rays).
    const double g2 = (E * ray1).norm(), g1 = (E.transpose() * ray2).norm();
    const double error = std::sqrt(ComputeSquaredSphericalSampsonError(ray1, moved, E));
    EXPECT_NEAR(error, angle * g2 / std::hypot(g1, g2), 1e-3 * angle);
  }
}

// LO-RANSAC on rays: 30 % outliers, 1 milliradian of noise, the 360-degree scene.
TEST(EssentialMatrixFromRays, RansacFindsThePoseAmongOutliers) {
  SetPRNGSeed(23);
  RayScene scene = RandomRayScene(400);
  std::vector<char> is_inlier(scene.rays1.size());
  for (size_t i = 0; i < scene.rays1.size(); ++i) {
    is_inlier[i] = i % 10 >= 3;
    const auto jitter = [](const Eigen::Vector3d& ray) {
      return (ray + 1e-3 *
                        Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1),
                                        RandomGaussian(0, 1)) /
                        std::sqrt(3.0))
          .normalized();
    };
    scene.rays1[i] = jitter(scene.rays1[i]);
    scene.rays2[i] = is_inlier[i] ? jitter(scene.rays2[i]) : RandomUnitVector();
  }
  RansacOptions options;
  options.max_error = 3e-3;
  const LoRansac<EssentialMatrixFivePointRayEstimator, EssentialMatrixEightPointRayEstimator>
      ransac(options);
  const auto report = ransac.Estimate(scene.rays1, scene.rays2);
  ASSERT_TRUE(report.success);
  size_t inliers_kept = 0, outliers_kept = 0;
  for (size_t i = 0; i < is_inlier.size(); ++i) {
    if (report.inlier_mask[i]) (is_inlier[i] ? inliers_kept : outliers_kept)++;
  }
  EXPECT_GE(inliers_kept, 0.95 * 280);
  EXPECT_LE(outliers_kept, 12u);
  EXPECT_LT(ProjectiveDistance(report.model, EssentialFromPose(scene.cam2_from_cam1)), 0.01);
}

}  // namespace
}  // namespace parallax
