#include "parallax/estimators/solvers/homography_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <limits>

#include "parallax/estimators/testing/two_view_scene.h"
#include "parallax/geometry/rigid3.h"
#include "parallax/math/random.h"
#include "parallax/optim/ransac.h"

namespace parallax {
namespace {

using test::Head;
using test::kImageHeight;
using test::kImageWidth;
using test::ProjectiveDistance;
using test::RandomImagePoint;
using test::TwoViewScene;

// Random points of a plane seen by two cameras (focal lengths 1000 and 900 px).
TwoViewScene RandomPlaneScene(int num_points) {
  test::TwoViewSceneOptions options;
  options.focal2 = 900;
  return test::RandomPlanarTwoViewScene(num_points, options);
}

TEST(HomographyMatrix, RecoversExactModel) {
  for (int trial = 0; trial < 20; ++trial) {
    const TwoViewScene scene = RandomPlaneScene(100);
    std::vector<Eigen::Matrix3d> models;
    for (size_t count : {size_t{4}, size_t{5}, size_t{100}}) {
      EstimateHomographyMatrix(Head(scene.points1, count), Head(scene.points2, count), &models);
      ASSERT_EQ(models.size(), 1u);
      EXPECT_LT(ProjectiveDistance(models[0], scene.TrueH()), 1e-8) << "N = " << count;
      EXPECT_NEAR(models[0].norm(), 1.0, 1e-12);
    }
  }
}

TEST(HomographyMatrix, RefusesDegenerateInput) {
  const TwoViewScene scene = RandomPlaneScene(10);
  std::vector<Eigen::Matrix3d> models = {Eigen::Matrix3d::Identity()};
  EstimateHomographyMatrix(Head(scene.points1, 3), Head(scene.points2, 3), &models);
  EXPECT_TRUE(models.empty());
  std::vector<Eigen::Vector2d> bad = Head(scene.points1, 6);
  bad[1].x() = std::numeric_limits<double>::quiet_NaN();
  EstimateHomographyMatrix(Head(bad, 4), Head(scene.points2, 4), &models);
  EXPECT_TRUE(models.empty());
  bad[1].x() = std::numeric_limits<double>::infinity();
  EstimateHomographyMatrix(bad, Head(scene.points2, 6), &models);
  EXPECT_TRUE(models.empty());
  // Three of four points on a line (and all points on a line): H is not determined.
  const Eigen::Matrix3d H_true = scene.TrueH();
  const auto map = [&](const Eigen::Vector2d& point) {
    return (H_true * point.homogeneous()).hnormalized().eval();
  };
  std::vector<Eigen::Vector2d> collinear1 = {{100, 100}, {200, 150}, {400, 250}, {300, 600}};
  std::vector<Eigen::Vector2d> collinear2;
  for (const Eigen::Vector2d& point : collinear1) collinear2.push_back(map(point));
  EstimateHomographyMatrix(collinear1, collinear2, &models);
  EXPECT_TRUE(models.empty());
  collinear1[3] = {600, 350};
  collinear1.push_back({700, 400});
  collinear2.clear();
  for (const Eigen::Vector2d& point : collinear1) collinear2.push_back(map(point));
  EstimateHomographyMatrix(collinear1, collinear2, &models);
  EXPECT_TRUE(models.empty());
  // One point repeated.
  const std::vector<Eigen::Vector2d> same(4, Eigen::Vector2d(5, 5));
  EstimateHomographyMatrix(same, same, &models);
  EXPECT_TRUE(models.empty());
}

TEST(HomographyMatrix, RefusesSamplesThatFoldThePlane) {
  // A 4-point sample whose exact homography sends one point beyond the line at infinity.
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  H(2, 0) = 0.01;  // (H x)_z = 0.01 x + 1 changes sign at x = -100.
  const std::vector<Eigen::Vector2d> points1 = {{0, 0}, {50, 0}, {0, 50}, {-200, 30}};
  std::vector<Eigen::Vector2d> points2;
  for (const Eigen::Vector2d& point : points1) {
    points2.push_back((H * point.homogeneous()).hnormalized());
  }
  std::vector<Eigen::Matrix3d> models;
  EstimateHomographyMatrix(points1, points2, &models);
  EXPECT_TRUE(models.empty());
  // The same points on one side are accepted.
  points2[3] = (H * Eigen::Vector3d(-50, 30, 1)).hnormalized();
  std::vector<Eigen::Vector2d> front = points1;
  front[3] = {-50, 30};
  EstimateHomographyMatrix(front, points2, &models);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_LT(ProjectiveDistance(models[0], H), 1e-10);
}

TEST(HomographyLoRansac, NoiseAndFortyPercentOutliers) {
  for (int trial = 0; trial < 3; ++trial) {
    TwoViewScene scene = RandomPlaneScene(1000);
    std::vector<char> is_inlier(scene.points1.size());
    for (size_t i = 0; i < scene.points1.size(); ++i) {
      is_inlier[i] = i % 5 >= 2;
      scene.points1[i] += Eigen::Vector2d(RandomGaussian(0, 0.5), RandomGaussian(0, 0.5));
      if (is_inlier[i]) {
        scene.points2[i] += Eigen::Vector2d(RandomGaussian(0, 0.5), RandomGaussian(0, 0.5));
      } else {
        scene.points2[i] = RandomImagePoint();
      }
    }
    RansacOptions options;
    options.max_error = 3.0;
    const LoRansac<HomographyMatrixEstimator> ransac(options);
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
    // Transfer of the image centre within a pixel of the truth.
    const Eigen::Vector3d centre(kImageWidth / 2, kImageHeight / 2, 1);
    EXPECT_LT(
        ((report.model * centre).hnormalized() - (scene.TrueH() * centre).hnormalized()).norm(),
        1.0);
  }
}

}  // namespace
}  // namespace parallax
