#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/geometry/rigid3.h"
#include "parallax/optim/ransac.h"
#include "parallax/scene/camera.h"

namespace parallax {

struct AbsolutePoseEstimationOptions {
  // P3P/EPnP LO-RANSAC; max_error is the reprojection error in pixels (converted to the
  // camera's normalised plane). The mapper derives one seed per image from this one.
  RansacOptions ransac = [] {
    RansacOptions options;
    options.max_error = 12.0;
    options.confidence = 0.99999;
    options.max_num_trials = 10000;
    options.min_inlier_ratio = 0.1;
    return options;
  }();
  void Check() const;
};

struct AbsolutePoseReport {
  bool success = false;
  Rigid3d cam_from_world;
  size_t num_inliers = 0;
  size_t num_trials = 0;
  std::vector<char> inlier_mask;
};

// Calibrated pose from 2D-3D correspondences: P3P minimal samples inside LO-RANSAC, EPnP on
// the inliers as local optimisation. points2D in pixels of `camera`.
AbsolutePoseReport EstimateAbsolutePose(const Camera& camera,
                                        const std::vector<Eigen::Vector2d>& points2D,
                                        const std::vector<Eigen::Vector3d>& points3D,
                                        const AbsolutePoseEstimationOptions& options);

struct AbsolutePoseRefinementOptions {
  double loss_scale_px = 1.0;  // Cauchy loss scale on reprojection error, pixels.
  int max_num_iterations = 100;
  // With the intrinsics constant (the mapper's case), stops after a step that lowered the
  // robust cost by at most this fraction of it.
  double min_relative_decrease = 1e-10;
  bool refine_focal_length = false;
  bool refine_extra_params = false;
  void Check() const;
};

// Non-linear refinement (Levenberg-Marquardt) of the pose on the inliers under a Cauchy loss,
// optionally with the camera's focal length and distortion (then through Ceres). False when
// the solver failed.
bool RefineAbsolutePose(const AbsolutePoseRefinementOptions& options,
                        const std::vector<char>& inlier_mask,
                        const std::vector<Eigen::Vector2d>& points2D,
                        const std::vector<Eigen::Vector3d>& points3D, Rigid3d* cam_from_world,
                        Camera* camera);

}  // namespace parallax
