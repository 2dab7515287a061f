#pragma once

#include <Eigen/Core>

namespace parallax {

using Matrix3x4d = Eigen::Matrix<double, 3, 4>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

}  // namespace parallax
