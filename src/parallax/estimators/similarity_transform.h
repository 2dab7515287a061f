#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/geometry/sim3.h"
#include "parallax/optim/ransac.h"

namespace parallax {

struct Sim3dRansacReport {
  bool success = false;
  Sim3d dst_from_src;
  size_t num_inliers = 0;
  std::vector<char> inlier_mask;
};

// The RANSAC options of EstimateSim3dRansac: inliers within `max_error` (dst units), up to
// 2,000 trials, confidence 0.9999, inlier ratios down to 0.1.
RansacOptions Sim3dRansacOptions(double max_error);

// Robust similarity dst = s R src + t: Umeyama on 3-point samples inside LO-RANSAC, refit on
// all inliers. `options.max_error` is the inlier distance in dst units. One bad
// correspondence (a badly placed camera) cannot skew the result.
Sim3dRansacReport EstimateSim3dRansac(const std::vector<Eigen::Vector3d>& src,
                                      const std::vector<Eigen::Vector3d>& dst,
                                      const RansacOptions& options);

}  // namespace parallax
