#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "parallax/geometry/sim3.h"

namespace parallax {

// Least-squares similarity dst = s R src + t (Umeyama, PAMI 1991). Needs >= 3 non-collinear
// points; returns nullopt for degenerate or non-finite input.
std::optional<Sim3d> EstimateSim3d(const std::vector<Eigen::Vector3d>& src,
                                   const std::vector<Eigen::Vector3d>& dst);

}  // namespace parallax
