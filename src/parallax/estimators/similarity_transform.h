#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/geometry/sim3.h"

namespace parallax {

struct Sim3dRansacReport {
  bool success = false;
  Sim3d dst_from_src;
  size_t num_inliers = 0;
  std::vector<char> inlier_mask;
};

// Robust similarity dst = s R src + t: Umeyama on 3-point samples inside LO-RANSAC, refit on
// all inliers. `max_error` is the inlier distance in dst units. One bad correspondence (a
// badly placed camera) cannot skew the result.
Sim3dRansacReport EstimateSim3dRansac(const std::vector<Eigen::Vector3d>& src,
                                      const std::vector<Eigen::Vector3d>& dst, double max_error,
                                      int max_num_trials = 2000);

}  // namespace parallax
