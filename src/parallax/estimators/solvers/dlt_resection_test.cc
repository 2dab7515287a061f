#include "parallax/estimators/solvers/dlt_resection.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>

#include "parallax/math/random.h"
#include "parallax/optim/ransac.h"

namespace parallax {
namespace {

struct Camera3x4 {
  Eigen::Matrix3d K;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Matrix3x4d P() const {
    Matrix3x4d Rt;
    Rt << R, t;
    return K * Rt;
  }
};

Camera3x4 RandomCamera() {
  Camera3x4 camera;
  camera.K << RandomUniformReal(800, 1500), RandomUniformReal(-2, 2), RandomUniformReal(400, 600),
      0, RandomUniformReal(800, 1500), RandomUniformReal(300, 500), 0, 0, 1;
  const Eigen::Vector3d axis(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                             RandomUniformReal(-1, 1));
  camera.R =
      Eigen::AngleAxisd(RandomUniformReal(-M_PI, M_PI), axis.normalized()).toRotationMatrix();
  camera.t =
      Eigen::Vector3d(RandomUniformReal(-3, 3), RandomUniformReal(-3, 3), RandomUniformReal(-3, 3));
  return camera;
}

// Points in front of the camera at depths 4 to 10, spread over the view.
void RandomPoints(const Camera3x4& camera, size_t num_points,
                  std::vector<Eigen::Vector2d>* points2D, std::vector<Eigen::Vector3d>* points3D) {
  points2D->clear();
  points3D->clear();
  for (size_t i = 0; i < num_points; ++i) {
    const Eigen::Vector3d point_in_cam =
        RandomUniformReal(4, 10) *
        Eigen::Vector3d(RandomUniformReal(-0.5, 0.5), RandomUniformReal(-0.4, 0.4), 1);
    points3D->push_back(camera.R.transpose() * (point_in_cam - camera.t));
    points2D->push_back((camera.K * point_in_cam).hnormalized());
  }
}

double RelativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / expected.norm();
}

TEST(SolveDLTResection, RecoversExactProjectionMatrix) {
  for (size_t num_points : {6, 7, 20, 500}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Camera3x4 camera = RandomCamera();
      std::vector<Eigen::Vector2d> points2D;
      std::vector<Eigen::Vector3d> points3D;
      RandomPoints(camera, num_points, &points2D, &points3D);
      std::vector<Matrix3x4d> proj_matrices;
      SolveDLTResection(points2D, points3D, &proj_matrices);
      ASSERT_EQ(proj_matrices.size(), 1u);
      const Matrix3x4d truth = camera.P();  // Third row of K R has unit norm already.
      EXPECT_LT(RelativeError(proj_matrices[0], truth), 1e-8) << num_points;

      Eigen::Matrix3d K, R;
      Eigen::Vector3d t;
      ASSERT_TRUE(DecomposeProjectionMatrix(proj_matrices[0], &K, &R, &t));
      EXPECT_LT(RelativeError(K, camera.K), 1e-8);
      EXPECT_LT(RelativeError(R, camera.R), 1e-8);
      EXPECT_LT(RelativeError(t, camera.t), 1e-8);
    }
  }
}

TEST(DecomposeProjectionMatrix, AnyScaleAndSign) {
  for (int trial = 0; trial < 100; ++trial) {
    const Camera3x4 camera = RandomCamera();
    const double scale = (trial % 2 ? -1 : 1) * RandomUniformReal(1e-3, 1e3);
    Eigen::Matrix3d K, R;
    Eigen::Vector3d t;
    ASSERT_TRUE(DecomposeProjectionMatrix(scale * camera.P(), &K, &R, &t));
    EXPECT_LT(RelativeError(K, camera.K), 1e-12);
    EXPECT_LT(RelativeError(R, camera.R), 1e-12);
    EXPECT_LT(RelativeError(t, camera.t), 1e-12);
    EXPECT_NEAR(R.determinant(), 1, 1e-12);
    EXPECT_GT(K(0, 0), 0);
    EXPECT_GT(K(1, 1), 0);
    EXPECT_EQ(K(1, 0), 0);
    EXPECT_EQ(K(2, 0), 0);
    EXPECT_EQ(K(2, 1), 0);
  }
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
  Matrix3x4d singular = Matrix3x4d::Zero();
  singular(0, 0) = singular(1, 1) = 1;
  EXPECT_FALSE(DecomposeProjectionMatrix(singular, &K, &R, &t));
  EXPECT_FALSE(DecomposeProjectionMatrix(Matrix3x4d::Zero(), &K, &R, &t));
  Matrix3x4d bad = RandomCamera().P();
  bad(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(DecomposeProjectionMatrix(bad, &K, &R, &t));
}

TEST(SolveDLTResection, NoisyPointsWithOutliersInRansac) {
  const Camera3x4 camera = RandomCamera();
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  RandomPoints(camera, 300, &points2D, &points3D);
  std::vector<char> is_outlier(points2D.size(), 0);
  for (size_t i = 0; i < points2D.size(); ++i) {
    if (i % 5 == 0) {
      points2D[i] = Eigen::Vector2d(RandomUniformReal(0, 1000), RandomUniformReal(0, 800));
      is_outlier[i] = 1;
    } else {
      points2D[i] += Eigen::Vector2d(RandomGaussian(0, 0.5), RandomGaussian(0, 0.5));
    }
  }
  RansacOptions options;
  options.max_error = 4;
  const LoRansac<DLTResectionEstimator> ransac(options);
  const auto report = ransac.Estimate(points2D, points3D);
  ASSERT_TRUE(report.success);
  size_t num_true_inliers_found = 0;
  for (size_t i = 0; i < points2D.size(); ++i) {
    if (report.inlier_mask[i] && !is_outlier[i]) ++num_true_inliers_found;
  }
  EXPECT_GE(num_true_inliers_found, 0.95 * 240);
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
  ASSERT_TRUE(DecomposeProjectionMatrix(report.model, &K, &R, &t));
  EXPECT_LT(Eigen::AngleAxisd(R * camera.R.transpose()).angle(), 0.5 * M_PI / 180);
  EXPECT_NEAR(K(0, 0), camera.K(0, 0), 0.03 * camera.K(0, 0));
}

TEST(SolveDLTResection, RefusesDegenerateInput) {
  const Camera3x4 camera = RandomCamera();
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  std::vector<Matrix3x4d> proj_matrices(2);

  // Too few points.
  RandomPoints(camera, 5, &points2D, &points3D);
  SolveDLTResection(points2D, points3D, &proj_matrices);
  EXPECT_TRUE(proj_matrices.empty());

  // Coplanar points (a plane at depth 6, tilted).
  points2D.clear();
  points3D.clear();
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d point_in_cam(RandomUniformReal(-2, 2), RandomUniformReal(-2, 2), 0);
    const Eigen::Vector3d tilted(point_in_cam.x(), point_in_cam.y(), 6 + 0.3 * point_in_cam.x());
    points3D.push_back(camera.R.transpose() * (tilted - camera.t));
    points2D.push_back((camera.K * tilted).hnormalized());
  }
  SolveDLTResection(points2D, points3D, &proj_matrices);
  EXPECT_TRUE(proj_matrices.empty());

  // Non-finite input.
  RandomPoints(camera, 20, &points2D, &points3D);
  points2D[3].x() = std::numeric_limits<double>::quiet_NaN();
  SolveDLTResection(points2D, points3D, &proj_matrices);
  EXPECT_TRUE(proj_matrices.empty());
  RandomPoints(camera, 20, &points2D, &points3D);
  points3D[9].z() = -std::numeric_limits<double>::infinity();
  SolveDLTResection(points2D, points3D, &proj_matrices);
  EXPECT_TRUE(proj_matrices.empty());

  // All points identical.
  points2D.assign(10, Eigen::Vector2d(1, 2));
  points3D.assign(10, Eigen::Vector3d(1, 2, 3));
  SolveDLTResection(points2D, points3D, &proj_matrices);
  EXPECT_TRUE(proj_matrices.empty());
}

}  // namespace
}  // namespace parallax
