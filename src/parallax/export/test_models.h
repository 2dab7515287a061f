#pragma once
// For the export tests: exact models seen through known cameras.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "parallax/geometry/look_at.h"
#include "parallax/scene/reconstruction.h"

namespace parallax::test {

// Strong barrel distortion: 640 x 480, f = 500, k = -0.2 (corners move by about 40 px).
inline Camera BarrelCamera() {
  Camera camera = Camera::Create(1, CameraModelId::kSimpleRadial, 500, 640, 480);
  camera.params[3] = -0.2;
  return camera;
}

inline Rigid3d RingPose(double azimuth_degrees) {
  const double azimuth = azimuth_degrees * M_PI / 180.0;
  return LookAt(Eigen::Vector3d(21 * std::cos(azimuth), 21 * std::sin(azimuth), 9.5),
                Eigen::Vector3d(0, 0, 3));
}

// Three views of 40 points through `camera` (id 1), keypoints exact; the points sit a little
// off the truth, so that reprojection errors are not all zero.
inline Reconstruction ExactModel(const Camera& camera = BarrelCamera()) {
  Reconstruction model;
  model.AddCamera(camera);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-4, 4);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 40; ++i)
    points.emplace_back(uniform(random), uniform(random), 3 + uniform(random) / 4);
  for (image_t image_id = 1; image_id <= 3; ++image_id) {
    Image image;
    image.image_id = image_id;
    image.camera_id = 1;
    image.name = "view" + std::to_string(image_id) + ".png";
    image.cam_from_world = RingPose(30.0 + 10.0 * image_id);
    for (const Eigen::Vector3d& point : points) {
      Point2D point2D;
      point2D.xy = model.GetCamera(1).ImgFromCam(image.cam_from_world * point);
      image.points2D.push_back(point2D);
    }
    model.AddImage(image);
    model.RegisterImage(image_id);
  }
  for (size_t index = 0; index < points.size(); ++index) {
    Track track;
    for (image_t image_id = 1; image_id <= 3; ++image_id) {
      track.AddElement(image_id, static_cast<point2D_t>(index));
    }
    // A little off the truth, so that reprojection errors are not all zero.
    model.AddPoint3D(points[index] + Eigen::Vector3d(0.01, -0.02, 0.005), track);
  }
  return model;
}

}  // namespace parallax::test
