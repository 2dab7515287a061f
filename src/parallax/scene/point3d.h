#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "parallax/scene/track.h"

namespace parallax {

struct Point3D {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Matrix<uint8_t, 3, 1> color = Eigen::Matrix<uint8_t, 3, 1>::Zero();
  // Mean reprojection error in pixels over the track; -1 until computed.
  double error = -1.0;
  Track track;
};

}  // namespace parallax
