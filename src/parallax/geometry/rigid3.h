#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <iosfwd>

#include "parallax/math/eigen_types.h"

namespace parallax {

// A rigid transform b_from_a: x_b = rotation * x_a + translation. Name instances after the
// frames they map (cam_from_world, cam2_from_cam1) and compose right to left.
struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
      : rotation(rotation), translation(translation) {}
  Rigid3d(const Eigen::Matrix3d& rotation_matrix, const Eigen::Vector3d& translation)
      : rotation(rotation_matrix), translation(translation) {}

  // [R | t] as a 3x4 matrix.
  Matrix3x4d ToMatrix() const;
  Rigid3d Inverse() const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return rotation * point + translation;
  }
};

// c_from_a = c_from_b * b_from_a.
inline Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a) {
  return Rigid3d((c_from_b.rotation * b_from_a.rotation).normalized(),
                 c_from_b.rotation * b_from_a.translation + c_from_b.translation);
}

std::ostream& operator<<(std::ostream& stream, const Rigid3d& transform);

// Angle in degrees of the rotation taking `a` to `b`.
double RotationAngleDegrees(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

// Centre of a camera in world coordinates given cam_from_world.
inline Eigen::Vector3d ProjectionCenter(const Rigid3d& cam_from_world) {
  return cam_from_world.rotation.inverse() * -cam_from_world.translation;
}

}  // namespace parallax
