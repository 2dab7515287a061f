#pragma once

// Test helpers shared by the geometry and estimator tests: random directions and poses drawn
// from the tests' seeded generator (math/random.h), and a distance between matrices defined
// up to scale.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "parallax/geometry/rigid3.h"
#include "parallax/math/random.h"

namespace parallax {
namespace test {

// A direction uniform on the unit sphere.
inline Eigen::Vector3d RandomUnitVector() {
  return Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
      .normalized();
}

// A pose anywhere: a rotation of up to pi about a random axis, a translation in the cube
// [-max_translation, max_translation]^3.
inline Rigid3d RandomCamFromWorld(double max_translation) {
  const Eigen::Vector3d axis(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                             RandomUniformReal(-1, 1));
  return Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(RandomUniformReal(-M_PI, M_PI), axis.normalized())),
      Eigen::Vector3d(RandomUniformReal(-max_translation, max_translation),
                      RandomUniformReal(-max_translation, max_translation),
                      RandomUniformReal(-max_translation, max_translation)));
}

// A relative pose: a rotation of min_angle to max_angle radians about a random axis, a unit
// baseline in a random direction.
inline Rigid3d RandomRelativePose(double min_angle, double max_angle) {
  const Eigen::Quaterniond rotation(
      Eigen::AngleAxisd(RandomUniformReal(min_angle, max_angle), RandomUnitVector()));
  return Rigid3d(rotation, RandomUnitVector());
}

// The distance of two matrices defined up to scale and sign (E, F, H), relative to their
// norms.
inline double ProjectiveDistance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d a_unit = a / a.norm();
  const Eigen::Matrix3d b_unit = b / b.norm();
  return std::min((a_unit - b_unit).norm(), (a_unit + b_unit).norm());
}

// K with one focal length and the principal point (cx, cy).
inline Eigen::Matrix3d CalibrationMatrix(double focal, double cx, double cy) {
  Eigen::Matrix3d K;
  K << focal, 0, cx, 0, focal, cy, 0, 0, 1;
  return K;
}

}  // namespace test
}  // namespace parallax
