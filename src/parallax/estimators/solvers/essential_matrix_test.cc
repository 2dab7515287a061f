#include "parallax/estimators/solvers/essential_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <limits>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/math/random.h"
#include "parallax/optim/ransac.h"

namespace parallax {
namespace {

constexpr double kFocal = 1000, kWidth = 1024, kHeight = 768;

Eigen::Vector3d RandomUnitVector() {
  return Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
      .normalized();
}

// Normalised coordinates of random points seen by two cameras (focal 1000, 1024 x 768 images).
struct Scene {
  Rigid3d cam2_from_cam1;
  std::vector<Eigen::Vector3d> points3D;
  std::vector<Eigen::Vector2d> points1, points2;
};

Scene RandomScene(int num_points, double max_rotation = 0.3) {
  Scene scene;
  scene.cam2_from_cam1 = Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(
                                     RandomUniformReal(0.0, max_rotation), RandomUnitVector())),
                                 RandomUnitVector());
  while (static_cast<int>(scene.points3D.size()) < num_points) {
    const Eigen::Vector3d point =
        RandomUniformReal(4, 10) * Eigen::Vector3d(RandomUniformReal(-0.5, 0.5) * kWidth / kFocal,
                                                   RandomUniformReal(-0.5, 0.5) * kHeight / kFocal,
                                                   1);
    const Eigen::Vector3d in_cam2 = scene.cam2_from_cam1 * point;
    if (in_cam2.z() < 0.5) continue;
    const Eigen::Vector2d point2 = in_cam2.hnormalized();
    if (std::abs(point2.x()) > 0.5 * kWidth / kFocal ||
        std::abs(point2.y()) > 0.5 * kHeight / kFocal) {
      continue;
    }
    scene.points3D.push_back(point);
    scene.points1.push_back(point.hnormalized());
    scene.points2.push_back(point2);
  }
  return scene;
}

double ProjectiveDistance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d a_unit = a / a.norm();
  const Eigen::Matrix3d b_unit = b / b.norm();
  return std::min((a_unit - b_unit).norm(), (a_unit + b_unit).norm());
}

std::vector<Eigen::Vector2d> Head(const std::vector<Eigen::Vector2d>& points, size_t count) {
  return std::vector<Eigen::Vector2d>(points.begin(), points.begin() + count);
}

TEST(EssentialMatrixFivePoint, OneSolutionIsExact) {
  for (int trial = 0; trial < 100; ++trial) {
    const Scene scene = RandomScene(5);
    const Eigen::Matrix3d E_true = EssentialFromPose(scene.cam2_from_cam1);
    std::vector<Eigen::Matrix3d> models;
    EstimateEssentialMatrixFivePoint(scene.points1, scene.points2, &models);
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
        EXPECT_LT(ComputeSquaredSampsonError(scene.points1[i], scene.points2[i], E), 1e-14);
      }
    }
    EXPECT_LT(best, 1e-8) << "trial " << trial;
  }
}

TEST(EssentialMatrixFivePoint, LeastSquaresAndPlanarScenes) {
  // More than five points: the least-squares null space still contains E.
  const Scene scene = RandomScene(30);
  std::vector<Eigen::Matrix3d> models;
  EstimateEssentialMatrixFivePoint(scene.points1, scene.points2, &models);
  double best = std::numeric_limits<double>::max();
  for (const Eigen::Matrix3d& E : models) {
    best = std::min(best, ProjectiveDistance(E, EssentialFromPose(scene.cam2_from_cam1)));
  }
  EXPECT_LT(best, 1e-8);
  // Coplanar points are not degenerate for the 5-point algorithm (Nistér 2004, sec. 1).
  Scene plane;
  plane.cam2_from_cam1 = scene.cam2_from_cam1;
  const Eigen::Vector3d normal =
      (Eigen::Vector3d(0, 0, -1) + 0.3 * RandomUnitVector()).normalized();
  while (plane.points1.size() < 5) {
    const Eigen::Vector3d ray(RandomUniformReal(-0.4, 0.4), RandomUniformReal(-0.3, 0.3), 1);
    const Eigen::Vector3d point = ray * normal.dot(Eigen::Vector3d(0, 0, 6)) / normal.dot(ray);
    const Eigen::Vector3d in_cam2 = plane.cam2_from_cam1 * point;
    if (in_cam2.z() < 0.5) continue;
    plane.points1.push_back(point.hnormalized());
    plane.points2.push_back(in_cam2.hnormalized());
  }
  EstimateEssentialMatrixFivePoint(plane.points1, plane.points2, &models);
  best = std::numeric_limits<double>::max();
  for (const Eigen::Matrix3d& E : models) {
    best = std::min(best, ProjectiveDistance(E, EssentialFromPose(plane.cam2_from_cam1)));
  }
  EXPECT_LT(best, 1e-8);
}

TEST(EssentialMatrixEightPoint, RecoversExactModel) {
  for (int trial = 0; trial < 20; ++trial) {
    const Scene scene = RandomScene(50);
    std::vector<Eigen::Matrix3d> models;
    for (size_t count : {size_t{8}, size_t{50}}) {
      EstimateEssentialMatrixEightPoint(Head(scene.points1, count), Head(scene.points2, count),
                                        &models);
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
  const Scene scene = RandomScene(10);
  std::vector<Eigen::Matrix3d> models = {Eigen::Matrix3d::Identity()};
  EstimateEssentialMatrixFivePoint(Head(scene.points1, 4), Head(scene.points2, 4), &models);
  EXPECT_TRUE(models.empty());
  EstimateEssentialMatrixEightPoint(Head(scene.points1, 7), Head(scene.points2, 7), &models);
  EXPECT_TRUE(models.empty());
  std::vector<Eigen::Vector2d> bad = Head(scene.points1, 8);
  bad[2].y() = std::numeric_limits<double>::quiet_NaN();
  EstimateEssentialMatrixFivePoint(Head(bad, 5), Head(scene.points2, 5), &models);
  EXPECT_TRUE(models.empty());
  EstimateEssentialMatrixFivePoint(bad, Head(scene.points2, 8), &models);
  EXPECT_TRUE(models.empty());
  bad[2].y() = -std::numeric_limits<double>::infinity();
  EstimateEssentialMatrixEightPoint(bad, Head(scene.points2, 8), &models);
  EXPECT_TRUE(models.empty());
  // The same correspondence five times, and points on one 3D line.
  const std::vector<Eigen::Vector2d> same1(5, scene.points1[0]), same2(5, scene.points2[0]);
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
    Scene scene = RandomScene(1000);
    const double noise = 0.5 / kFocal;
    std::vector<char> is_inlier(scene.points1.size());
    for (size_t i = 0; i < scene.points1.size(); ++i) {
      is_inlier[i] = i % 5 >= 2;
      scene.points1[i] += Eigen::Vector2d(RandomGaussian(0, noise), RandomGaussian(0, noise));
      if (is_inlier[i]) {
        scene.points2[i] += Eigen::Vector2d(RandomGaussian(0, noise), RandomGaussian(0, noise));
      } else {
        scene.points2[i] = Eigen::Vector2d(RandomUniformReal(-0.5, 0.5) * kWidth / kFocal,
                                           RandomUniformReal(-0.5, 0.5) * kHeight / kFocal);
      }
    }
    RansacOptions options;
    options.max_error = 1.5 / kFocal;  // 3 sigma of the 0.5 px noise.
    const LoRansac<EssentialMatrixFivePointEstimator, EssentialMatrixEightPointEstimator> ransac(
        options);
    const auto report = ransac.Estimate(scene.points1, scene.points2);
    ASSERT_TRUE(report.success);
    size_t inliers_kept = 0, outliers_kept = 0, num_true_inliers = 0;
    for (size_t i = 0; i < is_inlier.size(); ++i) {
      num_true_inliers += is_inlier[i];
      if (report.inlier_mask[i]) (is_inlier[i] ? inliers_kept : outliers_kept)++;
    }
    std::cerr << "kept " << inliers_kept << "/" << num_true_inliers << " inliers, " << outliers_kept
              << "/" << is_inlier.size() - num_true_inliers << " outliers\n";
    EXPECT_GE(inliers_kept, 0.95 * num_true_inliers);
    EXPECT_LE(outliers_kept, 0.01 * (inliers_kept + outliers_kept));
    // The relative pose from the model is within a fraction of a degree of the truth.
    Rigid3d estimated;
    std::vector<Eigen::Vector2d> inliers1, inliers2;
    for (size_t i = 0; i < is_inlier.size(); ++i) {
      if (report.inlier_mask[i]) {
        inliers1.push_back(scene.points1[i]);
        inliers2.push_back(scene.points2[i]);
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
