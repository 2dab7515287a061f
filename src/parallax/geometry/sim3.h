#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "parallax/geometry/rigid3.h"

namespace parallax {

// A similarity b_from_a: x_b = scale * rotation * x_a + translation.
struct Sim3d {
  double scale = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Sim3d() = default;
  Sim3d(double scale, const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
      : scale(scale), rotation(rotation), translation(translation) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return scale * (rotation * point) + translation;
  }
  Sim3d Inverse() const {
    const Eigen::Quaterniond inverse_rotation = rotation.inverse();
    return Sim3d(1.0 / scale, inverse_rotation, inverse_rotation * (-translation / scale));
  }
  Eigen::Matrix<double, 3, 4> ToMatrix() const {
    Eigen::Matrix<double, 3, 4> matrix;
    matrix.leftCols<3>() = scale * rotation.toRotationMatrix();
    matrix.col(3) = translation;
    return matrix;
  }
};

// Re-expresses a camera pose cam_from_a in frame b, given b_from_a. Cameras carry no scale,
// so the camera frame is rescaled: the result maps b into the same camera.
inline Rigid3d TransformCameraPose(const Sim3d& b_from_a, const Rigid3d& cam_from_a) {
  const Eigen::Quaterniond rotation =
      (cam_from_a.rotation * b_from_a.rotation.inverse()).normalized();
  return Rigid3d(rotation,
                 b_from_a.scale * cam_from_a.translation - rotation * b_from_a.translation);
}

}  // namespace parallax
