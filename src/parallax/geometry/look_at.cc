#include "parallax/geometry/look_at.h"

namespace parallax {

Rigid3d LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - center).normalized();
  Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
  if (right.norm() < 1e-9) right = forward.cross(Eigen::Vector3d::UnitY());
  right.normalize();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d rotation;
  rotation.row(0) = right.transpose();
  rotation.row(1) = down.transpose();
  rotation.row(2) = forward.transpose();
  return Rigid3d(rotation, -rotation * center);
}

}  // namespace parallax
