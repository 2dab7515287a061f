#include "parallax/estimators/solvers/epnp.h"

#include <gtest/gtest.h>

#include <limits>

#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"

namespace parallax {
namespace {

// A camera anywhere within 5 of the origin, turned any way.
Rigid3d RandomCamFromWorld() { return test::RandomCamFromWorld(5); }

struct Scene {
  Rigid3d cam_from_world;
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
};

// Points seen within +-0.6 normalised units at depths 3 to 9; `planar` puts them on a random
// plane through the view.
Scene RandomScene(size_t num_points, bool planar, double noise = 0) {
  Scene scene;
  scene.cam_from_world = RandomCamFromWorld();
  const Rigid3d world_from_cam = scene.cam_from_world.Inverse();
  const Eigen::Vector3d normal =
      Eigen::Vector3d(RandomUniformReal(-0.5, 0.5), RandomUniformReal(-0.5, 0.5), 1).normalized();
  for (size_t i = 0; i < num_points; ++i) {
    const Eigen::Vector3d ray(RandomUniformReal(-0.6, 0.6), RandomUniformReal(-0.6, 0.6), 1);
    // Plane normal . X = 6 in the camera frame.
    const double depth = planar ? 6.0 / normal.dot(ray) : RandomUniformReal(3, 9);
    const Eigen::Vector3d point_in_cam = depth * ray;
    scene.points3D.push_back(world_from_cam * point_in_cam);
    scene.points2D.push_back(point_in_cam.hnormalized() +
                             Eigen::Vector2d(RandomGaussian(0, noise), RandomGaussian(0, noise)));
  }
  return scene;
}

double RotationError(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation);
}
double TranslationError(const Rigid3d& a, const Rigid3d& b) {
  return (a.translation - b.translation).norm() / b.translation.norm();
}

TEST(SolveEPnP, RecoversExactPose) {
  for (size_t num_points : {4, 5, 6, 10, 50, 500}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Scene scene = RandomScene(num_points, /*planar=*/false);
      std::vector<Rigid3d> poses;
      SolveEPnP(scene.points2D, scene.points3D, &poses);
      ASSERT_EQ(poses.size(), 1u) << num_points;
      EXPECT_LT(RotationError(poses[0], scene.cam_from_world), 1e-8) << num_points;
      EXPECT_LT(TranslationError(poses[0], scene.cam_from_world), 1e-8) << num_points;
    }
  }
}

TEST(SolveEPnP, RecoversExactPoseOfPlanarScene) {
  for (size_t num_points : {4, 6, 20, 500}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Scene scene = RandomScene(num_points, /*planar=*/true);
      std::vector<Rigid3d> poses;
      SolveEPnP(scene.points2D, scene.points3D, &poses);
      ASSERT_EQ(poses.size(), 1u) << num_points;
      EXPECT_LT(RotationError(poses[0], scene.cam_from_world), 1e-8) << num_points;
      EXPECT_LT(TranslationError(poses[0], scene.cam_from_world), 1e-8) << num_points;
    }
  }
}

TEST(SolveEPnP, NoisyPointsGiveAccuratePose) {
  // 1e-3 normalised units is 1 px at a focal length of 1000 px.
  for (bool planar : {false, true}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Scene scene = RandomScene(200, planar, 1e-3);
      std::vector<Rigid3d> poses;
      SolveEPnP(scene.points2D, scene.points3D, &poses);
      ASSERT_EQ(poses.size(), 1u);
      EXPECT_LT(RotationError(poses[0], scene.cam_from_world), 2e-3) << planar;
      EXPECT_LT(TranslationError(poses[0], scene.cam_from_world), 1e-2) << planar;
      // A least-squares optimum: no worse than the truth on its own data.
      std::vector<double> estimate_errors, truth_errors;
      ComputeSquaredReprojectionErrors(scene.points2D, scene.points3D, poses[0], &estimate_errors);
      ComputeSquaredReprojectionErrors(scene.points2D, scene.points3D, scene.cam_from_world,
                                       &truth_errors);
      double estimate_cost = 0, truth_cost = 0;
      for (size_t i = 0; i < estimate_errors.size(); ++i) {
        estimate_cost += estimate_errors[i];
        truth_cost += truth_errors[i];
      }
      EXPECT_LE(estimate_cost, truth_cost * (1 + 1e-9));
    }
  }
}

TEST(RefineAbsolutePoseLeastSquares, ConvergesFromPerturbedPose) {
  const Scene scene = RandomScene(100, /*planar=*/false);
  Rigid3d pose = scene.cam_from_world;
  pose.rotation = pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(
                                      0.05, Eigen::Vector3d(1, -2, 0.5).normalized()));
  pose.translation += Eigen::Vector3d(0.1, -0.2, 0.1);
  ASSERT_TRUE(RefineAbsolutePoseLeastSquares(scene.points2D, scene.points3D, &pose, 20));
  EXPECT_LT(RotationError(pose, scene.cam_from_world), 1e-10);
  EXPECT_LT(TranslationError(pose, scene.cam_from_world), 1e-10);

  // Too few points in front of the camera.
  std::vector<Eigen::Vector2d> few2D(scene.points2D.begin(), scene.points2D.begin() + 2);
  std::vector<Eigen::Vector3d> few3D(scene.points3D.begin(), scene.points3D.begin() + 2);
  EXPECT_FALSE(RefineAbsolutePoseLeastSquares(few2D, few3D, &pose));
}

TEST(SolveEPnP, RefusesDegenerateInput) {
  Scene scene = RandomScene(10, /*planar=*/false);
  std::vector<Rigid3d> poses(3);
  // Too few points.
  SolveEPnP({scene.points2D.begin(), scene.points2D.begin() + 3},
            {scene.points3D.begin(), scene.points3D.begin() + 3}, &poses);
  EXPECT_TRUE(poses.empty());
  SolveEPnP({}, {}, &poses);
  EXPECT_TRUE(poses.empty());

  // Collinear world points.
  std::vector<Eigen::Vector3d> collinear;
  std::vector<Eigen::Vector2d> collinear2D;
  const Rigid3d& cam_from_world = scene.cam_from_world;
  for (int i = 0; i < 10; ++i) {
    collinear.push_back(cam_from_world.Inverse() * Eigen::Vector3d(0.1 * i, 0.05 * i, 4 + 0.2 * i));
    collinear2D.push_back((cam_from_world * collinear.back()).hnormalized());
  }
  SolveEPnP(collinear2D, collinear, &poses);
  EXPECT_TRUE(poses.empty());

  // Non-finite input.
  scene.points3D[4].y() = std::numeric_limits<double>::quiet_NaN();
  SolveEPnP(scene.points2D, scene.points3D, &poses);
  EXPECT_TRUE(poses.empty());
  scene.points3D[4].y() = 0;
  scene.points2D[7].x() = std::numeric_limits<double>::infinity();
  SolveEPnP(scene.points2D, scene.points3D, &poses);
  EXPECT_TRUE(poses.empty());
}

}  // namespace
}  // namespace parallax
