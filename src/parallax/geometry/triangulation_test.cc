#include "parallax/geometry/triangulation.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "parallax/geometry/rigid3.h"
#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;
using test::RandomUnitVector;

// A camera at `distance` from the origin in a random direction, looking at the origin.
Rigid3d RandomCameraLookingAtOrigin(double distance) {
  const Eigen::Vector3d center = distance * RandomUnitVector();
  const Eigen::Vector3d z = -center.normalized();
  const Eigen::Vector3d x = RandomUnitVector().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(cam_from_world, -cam_from_world * center);
}

Eigen::Vector3d RandomPointNearOrigin() {
  return Eigen::Vector3d(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                         RandomUniformReal(-1, 1));
}

TEST(TriangulatePoint, RecoversExactPoints) {
  for (int scene = 0; scene < 20; ++scene) {
    const Rigid3d cam1_from_world = RandomCameraLookingAtOrigin(RandomUniformReal(3, 10));
    const Rigid3d cam2_from_world = RandomCameraLookingAtOrigin(RandomUniformReal(3, 10));
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d point3D = RandomPointNearOrigin();
      const std::optional<Eigen::Vector3d> triangulated = TriangulatePoint(
          cam1_from_world.ToMatrix(), cam2_from_world.ToMatrix(),
          (cam1_from_world * point3D).hnormalized(), (cam2_from_world * point3D).hnormalized());
      ASSERT_TRUE(triangulated.has_value());
      EXPECT_THAT(*triangulated, EigenMatrixNear(point3D, 1e-8 * point3D.norm()));
    }
  }
}

TEST(TriangulatePoint, RefusesDegenerateInput) {
  const Rigid3d cam1_from_world = RandomCameraLookingAtOrigin(5);
  const Rigid3d cam2_from_world = RandomCameraLookingAtOrigin(5);
  const Eigen::Vector3d point3D(0.1, 0.2, -0.3);
  const Eigen::Vector2d point1 = (cam1_from_world * point3D).hnormalized();
  const Eigen::Vector2d point2 = (cam2_from_world * point3D).hnormalized();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(TriangulatePoint(cam1_from_world.ToMatrix(), cam2_from_world.ToMatrix(),
                                Eigen::Vector2d(nan, 0), point2));
  EXPECT_FALSE(TriangulatePoint(cam1_from_world.ToMatrix(), cam2_from_world.ToMatrix(), point1,
                                Eigen::Vector2d(0, inf)));
  // The same camera twice: the two rays coincide and the depth is undetermined.
  EXPECT_FALSE(
      TriangulatePoint(cam1_from_world.ToMatrix(), cam1_from_world.ToMatrix(), point1, point1));
  // Parallel rays from a pure translation: the point is at infinity.
  const Rigid3d shifted(cam1_from_world.rotation,
                        cam1_from_world.translation + Eigen::Vector3d(1, 0, 0));
  EXPECT_FALSE(TriangulatePoint(cam1_from_world.ToMatrix(), shifted.ToMatrix(), point1, point1));
}

TEST(TriangulateMultiViewPoint, RecoversExactPoints) {
  for (int scene = 0; scene < 20; ++scene) {
    const int num_views = 2 + scene % 6;
    std::vector<Matrix3x4d> cams_from_world;
    std::vector<Rigid3d> poses;
    for (int v = 0; v < num_views; ++v) {
      poses.push_back(RandomCameraLookingAtOrigin(RandomUniformReal(3, 10)));
      cams_from_world.push_back(poses.back().ToMatrix());
    }
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d point3D = RandomPointNearOrigin();
      std::vector<Eigen::Vector2d> points;
      for (const Rigid3d& pose : poses) points.push_back((pose * point3D).hnormalized());
      const std::optional<Eigen::Vector3d> triangulated =
          TriangulateMultiViewPoint(cams_from_world, points);
      ASSERT_TRUE(triangulated.has_value());
      EXPECT_THAT(*triangulated, EigenMatrixNear(point3D, 1e-8 * point3D.norm()));
    }
  }
}

TEST(TriangulateMultiViewPoint, AgreesWithTwoViewAndAveragesNoise) {
  std::vector<Matrix3x4d> cams_from_world;
  std::vector<Rigid3d> poses;
  for (int v = 0; v < 30; ++v) {
    poses.push_back(RandomCameraLookingAtOrigin(5));
    cams_from_world.push_back(poses.back().ToMatrix());
  }
  const Eigen::Vector3d point3D(0.3, -0.2, 0.1);
  std::vector<Eigen::Vector2d> exact, noisy;
  for (const Rigid3d& pose : poses) {
    exact.push_back((pose * point3D).hnormalized());
    noisy.push_back(exact.back() +
                    Eigen::Vector2d(RandomGaussian(0, 1e-3), RandomGaussian(0, 1e-3)));
  }
  const std::vector<Matrix3x4d> two_cams(cams_from_world.begin(), cams_from_world.begin() + 2);
  const std::vector<Eigen::Vector2d> two_points(exact.begin(), exact.begin() + 2);
  const auto multi = TriangulateMultiViewPoint(two_cams, two_points);
  const auto pair = TriangulatePoint(two_cams[0], two_cams[1], two_points[0], two_points[1]);
  ASSERT_TRUE(multi && pair);
  EXPECT_THAT(*multi, EigenMatrixNear(*pair, 1e-10));
  // 1e-3 normalised noise at depth 5 is ~5 mm per view; 30 views average it down.
  const auto averaged = TriangulateMultiViewPoint(cams_from_world, noisy);
  ASSERT_TRUE(averaged);
  EXPECT_THAT(*averaged, EigenMatrixNear(point3D, 3e-3));
}

TEST(TriangulateMultiViewPoint, RefusesBadInput) {
  const Rigid3d pose = RandomCameraLookingAtOrigin(5);
  EXPECT_FALSE(TriangulateMultiViewPoint({pose.ToMatrix()}, {Eigen::Vector2d(0, 0)}));
  EXPECT_FALSE(TriangulateMultiViewPoint({}, {}));
  EXPECT_THROW(TriangulateMultiViewPoint({pose.ToMatrix()}, {}), CheckError);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(TriangulateMultiViewPoint(
      {pose.ToMatrix(), pose.ToMatrix(), pose.ToMatrix()},
      {Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), Eigen::Vector2d(nan, 0)}));
  // One camera three times with one ray: the depth along the ray is undetermined.
  EXPECT_FALSE(TriangulateMultiViewPoint(
      {pose.ToMatrix(), pose.ToMatrix(), pose.ToMatrix()},
      {Eigen::Vector2d(0.1, 0), Eigen::Vector2d(0.1, 0), Eigen::Vector2d(0.1, 0)}));
}

TEST(CalculateTriangulationAngle, KnownGeometry) {
  const Eigen::Vector3d center1(0, 0, 0), center2(2, 0, 0);
  EXPECT_NEAR(CalculateTriangulationAngle(center1, center2, Eigen::Vector3d(1, 0, 1)), M_PI / 2,
              1e-14);
  EXPECT_NEAR(CalculateTriangulationAngle(center1, center2, Eigen::Vector3d(1, 0, std::sqrt(3.0))),
              M_PI / 3, 1e-14);
  // Symmetric in the centres, tiny for far points, near pi between the centres.
  const Eigen::Vector3d far(1, 0, 1e6);
  EXPECT_NEAR(CalculateTriangulationAngle(center1, center2, far), 2e-6, 1e-12);
  EXPECT_NEAR(CalculateTriangulationAngle(center2, center1, far), 2e-6, 1e-12);
  EXPECT_NEAR(CalculateTriangulationAngle(center1, center2, Eigen::Vector3d(1, 0, 1e-6)),
              M_PI - 2e-6, 1e-10);
}

TEST(HasPointPositiveDepth, FrontAndBack) {
  const Rigid3d cam_from_world(
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())),
      Eigen::Vector3d(0, 0, 2));
  // This camera looks along world -z from z = 2.
  EXPECT_TRUE(HasPointPositiveDepth(cam_from_world.ToMatrix(), Eigen::Vector3d(0.5, 0.5, 1)));
  EXPECT_FALSE(HasPointPositiveDepth(cam_from_world.ToMatrix(), Eigen::Vector3d(0, 0, 3)));
  EXPECT_FALSE(HasPointPositiveDepth(cam_from_world.ToMatrix(), Eigen::Vector3d(1, 0, 2)));
}

}  // namespace
}  // namespace parallax
