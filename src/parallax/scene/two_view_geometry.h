#pragma once

#include <Eigen/Core>

#include "parallax/feature/types.h"
#include "parallax/geometry/rigid3.h"

namespace parallax {

// The verified relation between two images, as COLMAP stores it in two_view_geometries.
struct TwoViewGeometry {
  // COLMAP's configuration codes (same integers in the database).
  enum Config : int {
    kUndefined = 0,
    kDegenerate = 1,
    kCalibrated = 2,    // E explains the matches (known intrinsics), enough parallax.
    kUncalibrated = 3,  // F explains the matches.
    kPlanar = 4,        // H explains them as well: a planar scene.
    kPanoramic = 5,     // H and no baseline: pure rotation.
    kPlanarOrPanoramic = 6,
    kWatermark = 7,
    kMultiple = 8,
  };

  int config = kUndefined;
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  // Relative pose (unit baseline) when it could be estimated.
  Rigid3d cam2_from_cam1;
  FeatureMatches inlier_matches;
  // Median triangulation angle in radians of the inliers (0 when unknown).
  double triangulation_angle = 0.0;
};

}  // namespace parallax
