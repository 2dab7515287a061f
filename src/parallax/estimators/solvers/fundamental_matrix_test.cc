#include "parallax/estimators/solvers/fundamental_matrix.h"

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
using test::ProjectiveDistance;
using test::RandomImagePoint;
using test::RandomTwoViewScene;
using test::RandomUnitVector;
using test::TwoViewScene;

TEST(HartleyNormalization, CentresAndScales) {
  const std::vector<Eigen::Vector2d> points = {{100, 200}, {300, 200}, {200, 400}, {200, 0}};
  Eigen::Matrix3d T;
  ASSERT_TRUE(ComputeHartleyNormalization(points, &T));
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  double mean_distance = 0;
  for (const Eigen::Vector2d& point : points) {
    const Eigen::Vector2d normalized = (T * point.homogeneous()).hnormalized();
    centroid += normalized / 4;
    mean_distance += normalized.norm() / 4;
  }
  EXPECT_LT(centroid.norm(), 1e-12);
  EXPECT_NEAR(mean_distance, std::sqrt(2.0), 1e-12);
  EXPECT_FALSE(ComputeHartleyNormalization({{5, 5}, {5, 5}}, &T));
  EXPECT_FALSE(ComputeHartleyNormalization({}, &T));
  EXPECT_FALSE(
      ComputeHartleyNormalization({{5, 5}, {std::numeric_limits<double>::infinity(), 5}}, &T));
}

TEST(FundamentalMatrixEightPoint, RecoversExactModel) {
  for (int trial = 0; trial < 20; ++trial) {
    const TwoViewScene scene = RandomTwoViewScene(100);
    std::vector<Eigen::Matrix3d> models;
    for (size_t count : {size_t{8}, size_t{9}, size_t{100}}) {
      EstimateFundamentalMatrixEightPoint(Head(scene.points1, count), Head(scene.points2, count),
                                          &models);
      ASSERT_EQ(models.size(), 1u);
      EXPECT_LT(ProjectiveDistance(models[0], scene.TrueF()), 1e-8) << "N = " << count;
      EXPECT_NEAR(models[0].norm(), 1.0, 1e-12);
      EXPECT_LT(std::abs(models[0].determinant()), 1e-12);
    }
  }
}

TEST(FundamentalMatrixSevenPoint, OneSolutionIsExact) {
  for (int trial = 0; trial < 50; ++trial) {
    const TwoViewScene scene = RandomTwoViewScene(7);
    std::vector<Eigen::Matrix3d> models;
    EstimateFundamentalMatrixSevenPoint(scene.points1, scene.points2, &models);
    ASSERT_TRUE(models.size() == 1 || models.size() == 3) << models.size();
    double best = std::numeric_limits<double>::max();
    for (const Eigen::Matrix3d& F : models) {
      best = std::min(best, ProjectiveDistance(F, scene.TrueF()));
      // Every candidate has rank 2 and fits all seven correspondences.
      EXPECT_LT(std::abs(F.determinant()), 1e-10);
      for (int i = 0; i < 7; ++i) {
        EXPECT_LT(ComputeSquaredSampsonError(scene.points1[i], scene.points2[i], F), 1e-12);
      }
    }
    EXPECT_LT(best, 1e-8);
  }
}

TEST(FundamentalMatrix, RefusesDegenerateInput) {
  const TwoViewScene scene = RandomTwoViewScene(20);
  std::vector<Eigen::Matrix3d> models = {Eigen::Matrix3d::Identity()};
  // Too few points.
  EstimateFundamentalMatrixSevenPoint(Head(scene.points1, 6), Head(scene.points2, 6), &models);
  EXPECT_TRUE(models.empty());
  EstimateFundamentalMatrixEightPoint(Head(scene.points1, 7), Head(scene.points2, 7), &models);
  EXPECT_TRUE(models.empty());
  // NaN / Inf.
  std::vector<Eigen::Vector2d> bad = Head(scene.points1, 8);
  bad[3].x() = std::numeric_limits<double>::quiet_NaN();
  EstimateFundamentalMatrixSevenPoint(Head(bad, 7), Head(scene.points2, 7), &models);
  EXPECT_TRUE(models.empty());
  bad[3].x() = std::numeric_limits<double>::infinity();
  EstimateFundamentalMatrixEightPoint(bad, Head(scene.points2, 8), &models);
  EXPECT_TRUE(models.empty());
  // All points identical.
  const std::vector<Eigen::Vector2d> same(8, Eigen::Vector2d(10, 20));
  EstimateFundamentalMatrixSevenPoint(Head(same, 7), Head(same, 7), &models);
  EXPECT_TRUE(models.empty());
  EstimateFundamentalMatrixEightPoint(same, same, &models);
  EXPECT_TRUE(models.empty());
}

TEST(FundamentalMatrix, RefusesCollinearAndCoplanarPoints) {
  for (int trial = 0; trial < 10; ++trial) {
    // 3D points on one line: collinear in both images.
    TwoViewScene line = test::EmptyTwoViewScene();
    TwoViewScene plane = line;  // The same cameras, no points yet.
    const Eigen::Vector3d origin(0, 0, 6), direction = RandomUnitVector();
    while (line.points3D.size() < 20) {
      line.Add(origin + RandomUniformReal(-2, 2) * direction);
    }
    // 3D points on one plane: F is a 3-parameter family (plus a homography).
    const Eigen::Vector3d normal =
        (Eigen::Vector3d(0, 0, -1) + 0.3 * RandomUnitVector()).normalized();
    while (plane.points3D.size() < 20) {
      const Eigen::Vector3d ray = plane.K1.inverse() * RandomImagePoint().homogeneous();
      // Plane through (0, 0, 6): normal . X = normal . (0, 0, 6).
      plane.Add(ray * normal.dot(origin) / normal.dot(ray));
    }
    for (const TwoViewScene* scene : {&line, &plane}) {
      std::vector<Eigen::Matrix3d> models;
      EstimateFundamentalMatrixSevenPoint(Head(scene->points1, 7), Head(scene->points2, 7),
                                          &models);
      EXPECT_TRUE(models.empty());
      EstimateFundamentalMatrixSevenPoint(scene->points1, scene->points2, &models);
      EXPECT_TRUE(models.empty());
      EstimateFundamentalMatrixEightPoint(Head(scene->points1, 8), Head(scene->points2, 8),
                                          &models);
      EXPECT_TRUE(models.empty());
      EstimateFundamentalMatrixEightPoint(scene->points1, scene->points2, &models);
      EXPECT_TRUE(models.empty());
    }
  }
}

TEST(FundamentalMatrixLoRansac, NoiseAndFortyPercentOutliers) {
  for (int trial = 0; trial < 3; ++trial) {
    TwoViewScene scene = RandomTwoViewScene(1000);
    std::vector<char> is_inlier(scene.points1.size());
    for (size_t i = 0; i < scene.points1.size(); ++i) {
      is_inlier[i] = i % 5 >= 2;  // 40 % outliers.
      scene.points1[i] += Eigen::Vector2d(RandomGaussian(0, 0.5), RandomGaussian(0, 0.5));
      if (is_inlier[i]) {
        scene.points2[i] += Eigen::Vector2d(RandomGaussian(0, 0.5), RandomGaussian(0, 0.5));
      } else {
        scene.points2[i] = RandomImagePoint();
      }
    }
    RansacOptions options;
    options.max_error = 1.5;  // 3 sigma of the 0.5 px noise.
    const LoRansac<FundamentalMatrixSevenPointEstimator, FundamentalMatrixEightPointEstimator>
        ransac(options);
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
    // The model explains the exact projections to well under a pixel.
    const TwoViewScene& truth = scene;
    double squared_error = 0;
    for (size_t i = 0; i < truth.points3D.size(); ++i) {
      const Eigen::Vector2d exact1 = (truth.K1 * truth.points3D[i]).hnormalized();
      const Eigen::Vector2d exact2 =
          (truth.K2 * (truth.cam2_from_cam1 * truth.points3D[i])).hnormalized();
      squared_error += ComputeSquaredSampsonError(exact1, exact2, report.model);
    }
    EXPECT_LT(std::sqrt(squared_error / truth.points3D.size()), 0.5);
  }
}

}  // namespace
}  // namespace parallax
