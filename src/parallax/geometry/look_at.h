#pragma once

#include <Eigen/Core>

#include "parallax/geometry/rigid3.h"

namespace parallax {

// cam_from_world of a camera at `center` looking at `target` in COLMAP's camera axes (x right,
// y down, z forward), with the image's up towards world +z; looking straight up or down, up
// is towards world -y instead. The synthetic scenes' cameras and the tests' are placed so.
Rigid3d LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target);

}  // namespace parallax
