#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "parallax/geometry/rigid3.h"
#include "parallax/util/types.h"

namespace parallax {

// A keypoint of an image and the 3D point it observes, if any.
struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  point3D_t point3D_id = kInvalidPoint3DId;
  bool HasPoint3D() const { return point3D_id != kInvalidPoint3DId; }
};

struct Image {
  image_t image_id = kInvalidImageId;
  camera_t camera_id = kInvalidCameraId;
  std::string name;
  Rigid3d cam_from_world;
  bool registered = false;
  std::vector<Point2D> points2D;
  // Number of points2D with a 3D point (kept up to date by Reconstruction).
  size_t num_points3D = 0;

  Eigen::Vector3d ProjectionCenter() const { return parallax::ProjectionCenter(cam_from_world); }
  // Optical axis in world coordinates.
  Eigen::Vector3d ViewingDirection() const {
    return cam_from_world.rotation.toRotationMatrix().row(2).transpose();
  }
  size_t NumPoints2D() const { return points2D.size(); }
};

}  // namespace parallax
