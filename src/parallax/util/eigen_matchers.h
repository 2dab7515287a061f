#pragma once

// gmock matchers for Eigen values, so a failed comparison prints both values and how far
// apart they are:
//   EXPECT_THAT(point, EigenMatrixNear(expected_point, 1e-9));
//   EXPECT_THAT(cam_from_world, Rigid3dNear(expected, 1e-9, 1e-9));

#include <gmock/gmock.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace parallax::test {

// Same shape, and no coefficient further than `tolerance` from the expected one.
MATCHER_P2(EigenMatrixNear, expected, tolerance,
           std::string(negation ? "is not" : "is") + " within " +
               ::testing::PrintToString(tolerance) +
               " of every coefficient of the expected matrix") {
  const Eigen::MatrixXd actual_matrix = arg;
  const Eigen::MatrixXd expected_matrix = expected;
  if (actual_matrix.rows() != expected_matrix.rows() ||
      actual_matrix.cols() != expected_matrix.cols()) {
    *result_listener << "is " << actual_matrix.rows() << "x" << actual_matrix.cols()
                     << ", expected " << expected_matrix.rows() << "x" << expected_matrix.cols();
    return false;
  }
  const double difference = (actual_matrix - expected_matrix).cwiseAbs().maxCoeff();
  *result_listener << "largest difference " << difference << "\nactual:\n"
                   << actual_matrix << "\nexpected:\n"
                   << expected_matrix;
  return difference <= tolerance;
}

// Rigid transforms (any type with a quaternion `rotation` and a vector `translation`, as
// Rigid3d): the rotation between them within `max_rotation_rad`, the translations within
// `max_translation` of each other.
MATCHER_P3(Rigid3dNear, expected, max_rotation_rad, max_translation,
           std::string(negation ? "is not" : "is") + " within " +
               ::testing::PrintToString(max_rotation_rad) + " rad and " +
               ::testing::PrintToString(max_translation) + " of the expected transform") {
  const double rotation = arg.rotation.angularDistance(expected.rotation);
  const double translation = (arg.translation - expected.translation).norm();
  *result_listener << "rotation differs by " << rotation << " rad, translation by " << translation;
  return rotation <= max_rotation_rad && translation <= max_translation;
}

// Similarities (Sim3d): scale within a relative `tolerance`, rotation within `tolerance` rad,
// translation within `tolerance` times the larger of 1 and its length.
MATCHER_P2(Sim3dNear, expected, tolerance,
           std::string(negation ? "is not" : "is") + " within " +
               ::testing::PrintToString(tolerance) + " of the expected similarity") {
  const double scale = std::abs(arg.scale - expected.scale) / expected.scale;
  const double rotation = arg.rotation.angularDistance(expected.rotation);
  const double translation =
      (arg.translation - expected.translation).norm() / std::max(1.0, expected.translation.norm());
  *result_listener << "scale differs by " << scale << " (relative), rotation by " << rotation
                   << " rad, translation by " << translation << " (relative)";
  return scale <= tolerance && rotation <= tolerance && translation <= tolerance;
}

}  // namespace parallax::test
