#include "parallax/geometry/rigid3.h"

#include <cmath>
#include <ostream>

namespace parallax {

Matrix3x4d Rigid3d::ToMatrix() const {
  Matrix3x4d matrix;
  matrix.leftCols<3>() = rotation.toRotationMatrix();
  matrix.col(3) = translation;
  return matrix;
}

Rigid3d Rigid3d::Inverse() const {
  const Eigen::Quaterniond inverse_rotation = rotation.inverse();
  return Rigid3d(inverse_rotation, inverse_rotation * -translation);
}

std::ostream& operator<<(std::ostream& stream, const Rigid3d& transform) {
  const auto& q = transform.rotation;
  stream << "Rigid3d(q=[" << q.w() << ", " << q.x() << ", " << q.y() << ", " << q.z() << "], t=["
         << transform.translation.transpose() << "])";
  return stream;
}

double RotationAngleDegrees(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return b.normalized().angularDistance(a.normalized()) * 180.0 / M_PI;
}

}  // namespace parallax
