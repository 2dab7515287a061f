#pragma once

// Test helpers shared by the two-view solver and estimator tests: random scenes of two views
// with their exact ground truth (pose, E, F, H), in pixels and in normalised coordinates.

#include <Eigen/Dense>
#include <vector>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/rigid3.h"
#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"

namespace parallax {
namespace test {

// Both images are kImageWidth x kImageHeight pixels, the principal point at their centre.
constexpr double kImageWidth = 1024, kImageHeight = 768;

struct TwoViewSceneOptions {
  double focal1 = 1000, focal2 = 1200;  // Pixels.
  // The relative rotation's angle is uniform in [min_rotation, max_rotation] (radians).
  double min_rotation = 0.05, max_rotation = 0.3;
};

// Points seen by two cameras: exact projections, nothing else.
struct TwoViewScene {
  Eigen::Matrix3d K1, K2;
  Rigid3d cam2_from_cam1;                                 // A unit baseline.
  std::vector<Eigen::Vector3d> points3D;                  // In cam1.
  std::vector<Eigen::Vector2d> points1, points2;          // Pixels.
  std::vector<Eigen::Vector2d> normalized1, normalized2;  // Normalised camera coordinates.
  // Planar scenes: normal . X = distance for the points X (cam1).
  Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();
  double plane_distance = 0;

  Eigen::Matrix3d TrueE() const { return EssentialFromPose(cam2_from_cam1); }
  Eigen::Matrix3d TrueF() const { return FundamentalFromEssential(TrueE(), K1, K2); }
  // H = K2 (R + t n^T / d) K1^-1, for planar scenes.
  Eigen::Matrix3d TrueH() const {
    return K2 *
           (cam2_from_cam1.rotation.toRotationMatrix() +
            cam2_from_cam1.translation * plane_normal.transpose() / plane_distance) *
           K1.inverse();
  }

  // Adds `point` (cam1) when it lies at least 0.5 in front of both cameras and inside
  // image 2; false otherwise.
  bool Add(const Eigen::Vector3d& point) {
    const Eigen::Vector3d in_cam2 = cam2_from_cam1 * point;
    if (point.z() < 0.5 || in_cam2.z() < 0.5) return false;
    const Eigen::Vector2d pixel2 = (K2 * in_cam2).hnormalized();
    if (pixel2.x() < 0 || pixel2.x() > kImageWidth || pixel2.y() < 0 || pixel2.y() > kImageHeight) {
      return false;
    }
    points3D.push_back(point);
    points1.push_back((K1 * point).hnormalized());
    points2.push_back(pixel2);
    normalized1.push_back(point.hnormalized());
    normalized2.push_back(in_cam2.hnormalized());
    return true;
  }
};

// A pixel uniform in the image.
inline Eigen::Vector2d RandomImagePoint() {
  return Eigen::Vector2d(RandomUniformReal(0, kImageWidth), RandomUniformReal(0, kImageHeight));
}

// The cameras and a random relative pose, no points yet.
inline TwoViewScene EmptyTwoViewScene(const TwoViewSceneOptions& options = {}) {
  TwoViewScene scene;
  scene.K1 = CalibrationMatrix(options.focal1, kImageWidth / 2, kImageHeight / 2);
  scene.K2 = CalibrationMatrix(options.focal2, kImageWidth / 2, kImageHeight / 2);
  scene.cam2_from_cam1 = RandomRelativePose(options.min_rotation, options.max_rotation);
  return scene;
}

// Points anywhere in image 1 at depths 4 to 10 that image 2 sees too.
inline TwoViewScene RandomTwoViewScene(int num_points, const TwoViewSceneOptions& options = {}) {
  TwoViewScene scene = EmptyTwoViewScene(options);
  while (static_cast<int>(scene.points3D.size()) < num_points) {
    const Eigen::Vector3d ray = scene.K1.inverse() * RandomImagePoint().homogeneous();
    scene.Add(RandomUniformReal(4, 10) * ray);
  }
  return scene;
}

// Points of one plane, about 6 in front of camera 1 and tilted by up to ~0.4 rad, that both
// images see.
inline TwoViewScene RandomPlanarTwoViewScene(int num_points,
                                             const TwoViewSceneOptions& options = {}) {
  TwoViewScene scene = EmptyTwoViewScene(options);
  scene.plane_normal = (Eigen::Vector3d(0, 0, 1) + 0.4 * RandomUnitVector()).normalized();
  scene.plane_distance = 6;
  while (static_cast<int>(scene.points3D.size()) < num_points) {
    const Eigen::Vector3d ray = scene.K1.inverse() * RandomImagePoint().homogeneous();
    scene.Add(ray * scene.plane_distance / scene.plane_normal.dot(ray));
  }
  return scene;
}

// The first `count` points.
inline std::vector<Eigen::Vector2d> Head(const std::vector<Eigen::Vector2d>& points, size_t count) {
  return std::vector<Eigen::Vector2d>(points.begin(), points.begin() + count);
}

}  // namespace test
}  // namespace parallax
