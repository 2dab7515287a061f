#include "parallax/estimators/solvers/p3p.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <limits>

#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// A camera anywhere within 5 of the origin, turned any way.
Rigid3d RandomCamFromWorld() { return test::RandomCamFromWorld(5); }

// A world point seen by the camera at normalised coordinates within +-0.6 and depth 2 to 10.
Eigen::Vector3d RandomVisiblePoint(const Rigid3d& cam_from_world) {
  const Eigen::Vector3d point_in_cam =
      RandomUniformReal(2, 10) *
      Eigen::Vector3d(RandomUniformReal(-0.6, 0.6), RandomUniformReal(-0.6, 0.6), 1);
  return cam_from_world.Inverse() * point_in_cam;
}

// Rotation angle (radians) plus relative translation error of the closest candidate.
double ClosestPoseError(const std::vector<Rigid3d>& candidates, const Rigid3d& truth) {
  double best = std::numeric_limits<double>::max();
  for (const Rigid3d& candidate : candidates) {
    const double error =
        candidate.rotation.angularDistance(truth.rotation) +
        (candidate.translation - truth.translation).norm() / truth.translation.norm();
    best = std::min(best, error);
  }
  return best;
}

TEST(SolveP3P, RecoversExactPoseAmongCandidates) {
  int num_failures = 0;
  double worst_error = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Rigid3d truth = RandomCamFromWorld();
    std::array<Eigen::Vector3d, 3> points, rays;
    for (int i = 0; i < 3; ++i) {
      points[i] = RandomVisiblePoint(truth);
      rays[i] = truth * points[i];
      if (trial % 2 == 0) rays[i].normalize();
    }
    std::vector<Rigid3d> candidates;
    SolveP3P(rays, points, &candidates);
    EXPECT_LE(candidates.size(), 4u);
    const double error = candidates.empty() ? 1.0 : ClosestPoseError(candidates, truth);
    worst_error = std::max(worst_error, error);
    if (error > 1e-8) ++num_failures;

    // Every candidate explains the three observations.
    for (const Rigid3d& candidate : candidates) {
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d point_in_cam = candidate * points[i];
        EXPECT_GT(point_in_cam.z(), 0);
        EXPECT_THAT(point_in_cam.normalized(), EigenMatrixNear(rays[i].normalized(), 1e-6));
      }
    }
  }
  EXPECT_EQ(num_failures, 0) << "worst error " << worst_error;
}

TEST(SolveP3P, EstimatorUsesNormalisedPoints) {
  const Rigid3d truth = RandomCamFromWorld();
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  for (int i = 0; i < 3; ++i) {
    points3D.push_back(RandomVisiblePoint(truth));
    points2D.push_back((truth * points3D.back()).hnormalized());
  }
  const P3PEstimator estimator;
  std::vector<Rigid3d> candidates;
  estimator.Estimate(points2D, points3D, &candidates);
  ASSERT_FALSE(candidates.empty());
  EXPECT_LT(ClosestPoseError(candidates, truth), 1e-8);

  // Residuals: zero for the truth, huge for a point behind the camera.
  points3D.push_back(truth.Inverse() * Eigen::Vector3d(0.1, 0.2, -3));
  points2D.push_back(Eigen::Vector2d(0.1, 0.2));
  std::vector<double> residuals;
  estimator.Residuals(points2D, points3D, truth, &residuals);
  ASSERT_EQ(residuals.size(), 4u);
  for (int i = 0; i < 3; ++i) EXPECT_LT(residuals[i], 1e-20);
  EXPECT_EQ(residuals[3], std::numeric_limits<double>::max());
}

TEST(SolveP3P, RefusesDegenerateInput) {
  const Rigid3d truth = RandomCamFromWorld();
  std::array<Eigen::Vector3d, 3> points, rays;
  // Collinear world points.
  const Eigen::Vector3d origin = RandomVisiblePoint(truth);
  const Eigen::Vector3d direction = RandomVisiblePoint(truth) - origin;
  for (int i = 0; i < 3; ++i) {
    points[i] = origin + (0.5 * i) * direction;
    rays[i] = truth * points[i];
  }
  std::vector<Rigid3d> candidates(2);
  SolveP3P(rays, points, &candidates);
  EXPECT_TRUE(candidates.empty());

  // Coincident world points.
  for (int i = 0; i < 3; ++i) points[i] = origin;
  SolveP3P(rays, points, &candidates);
  EXPECT_TRUE(candidates.empty());

  // Non-finite input and zero rays.
  for (int i = 0; i < 3; ++i) {
    points[i] = RandomVisiblePoint(truth);
    rays[i] = truth * points[i];
  }
  std::array<Eigen::Vector3d, 3> bad_points = points, bad_rays = rays;
  bad_points[1].x() = std::numeric_limits<double>::quiet_NaN();
  SolveP3P(rays, bad_points, &candidates);
  EXPECT_TRUE(candidates.empty());
  bad_rays[2].z() = std::numeric_limits<double>::infinity();
  SolveP3P(bad_rays, points, &candidates);
  EXPECT_TRUE(candidates.empty());
  bad_rays[2].setZero();
  SolveP3P(bad_rays, points, &candidates);
  EXPECT_TRUE(candidates.empty());
}

}  // namespace
}  // namespace parallax
