#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// What one bundle adjustment optimises, gathered once from a config: the pose, point and
// camera blocks (pointers into the reconstruction) and the observations between them. Both
// solvers (Ceres and the dense Schur LM) work from this list.
struct BundleAdjustmentProblem {
  struct Pose {
    image_t image_id = kInvalidImageId;
    Rigid3d* cam_from_world = nullptr;
    bool constant = false;
    std::array<bool, 3> constant_translation = {false, false, false};  // Gauge coordinates.
    size_t num_observations = 0;
    // Part of the reduced camera system: refined and observed.
    bool IsVariable() const { return !constant && num_observations > 0; }
  };
  struct Point {
    Eigen::Vector3d* xyz = nullptr;
    bool constant = false;
  };
  struct CameraBlock {
    Camera* camera = nullptr;
    std::vector<int> free_params;  // Refined parameter indices, ascending; empty: constant.
    size_t num_observations = 0;
    bool IsVariable() const { return !free_params.empty() && num_observations > 0; }
  };
  struct Observation {
    int pose = 0;  // Indices into poses, points, cameras.
    int point = 0;
    int camera = 0;
    Eigen::Vector2d xy;
  };
  // Points by id; poses of the config's images (id order), then of the other registered
  // images that see those points (constant); cameras of the config's images, then the others
  // (constant). Observations: the config's images in order, then the other views per point.
  std::vector<Pose> poses;
  std::vector<Point> points;
  std::vector<CameraBlock> cameras;
  std::vector<Observation> observations;
  size_t num_config_images = 0;  // With observations; sets the linear solver.
};

BundleAdjustmentProblem GatherBundleAdjustmentProblem(const BundleAdjustmentOptions& options,
                                                      const BundleAdjustmentConfig& config,
                                                      Reconstruction* reconstruction);

}  // namespace parallax
