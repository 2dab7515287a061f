#include "parallax/estimators/bundle_adjustment_problem.h"

#include <algorithm>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// The camera parameters the refine flags leave free, ascending.
std::vector<int> FreeCameraParamIdxs(const BundleAdjustmentOptions& options,
                                     CameraModelId model_id) {
  std::vector<int> free;
  const auto add = [&](bool refine, const std::vector<int>& idxs) {
    if (refine) free.insert(free.end(), idxs.begin(), idxs.end());
  };
  add(options.refine_focal_length, CameraModelFocalIdxs(model_id));
  add(options.refine_principal_point, CameraModelPrincipalPointIdxs(model_id));
  add(options.refine_extra_params, CameraModelExtraIdxs(model_id));
  std::sort(free.begin(), free.end());
  return free;
}

}  // namespace

BundleAdjustmentProblem GatherBundleAdjustmentProblem(const BundleAdjustmentOptions& options,
                                                      const BundleAdjustmentConfig& config,
                                                      Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  for (const auto& [image_id, coordinate] : config.constant_translation_coordinates) {
    PARALLAX_CHECK(coordinate >= 0 && coordinate < 3);
  }
  BundleAdjustmentProblem problem;

  // The config's images and cameras, the points they observe, and those points' other
  // registered views (constant poses, as COLMAP does). Ordered sets throughout.
  std::set<camera_t> variable_camera_ids;
  std::vector<point3D_t> point3D_ids;
  for (const image_t image_id : config.images) {
    const Image& image = reconstruction->GetImage(image_id);
    variable_camera_ids.insert(image.camera_id);
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D()) point3D_ids.push_back(point2D.point3D_id);
    }
  }
  std::sort(point3D_ids.begin(), point3D_ids.end());
  point3D_ids.erase(std::unique(point3D_ids.begin(), point3D_ids.end()), point3D_ids.end());
  const std::unordered_set<image_t> config_image_ids(config.images.begin(), config.images.end());
  std::set<image_t> outside_image_ids;
  std::set<camera_t> outside_camera_ids;
  for (const point3D_t point3D_id : point3D_ids) {
    for (const TrackElement& element : reconstruction->GetPoint3D(point3D_id).track.elements) {
      if (config_image_ids.count(element.image_id) > 0) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      if (!image.registered) continue;
      outside_image_ids.insert(element.image_id);
      if (variable_camera_ids.count(image.camera_id) == 0) {
        outside_camera_ids.insert(image.camera_id);
      }
    }
  }

  // Hash maps for the lookups (one per observation); the problem's order stays that of the
  // sorted ids above.
  std::unordered_map<point3D_t, int> point_index;
  point_index.reserve(point3D_ids.size());
  for (const point3D_t point3D_id : point3D_ids) {
    point_index.emplace(point3D_id, static_cast<int>(problem.points.size()));
    problem.points.push_back({&reconstruction->GetPoint3D(point3D_id).xyz,
                              config.constant_points.count(point3D_id) > 0});
  }
  std::unordered_map<image_t, int> pose_index;
  const auto add_pose = [&](image_t image_id, bool constant) {
    BundleAdjustmentProblem::Pose pose;
    pose.image_id = image_id;
    pose.cam_from_world = &reconstruction->GetImage(image_id).cam_from_world;
    pose.constant = constant || config.constant_poses.count(image_id) > 0;
    for (int c = 0; c < 3; ++c) {
      pose.constant_translation[c] =
          config.constant_translation_coordinates.count({image_id, c}) > 0;
    }
    pose_index.emplace(image_id, static_cast<int>(problem.poses.size()));
    problem.poses.push_back(pose);
  };
  for (const image_t image_id : config.images) add_pose(image_id, false);
  for (const image_t image_id : outside_image_ids) add_pose(image_id, true);
  std::unordered_map<camera_t, int> camera_index;
  const auto add_camera = [&](camera_t camera_id, bool constant) {
    Camera& camera = reconstruction->GetCamera(camera_id);
    BundleAdjustmentProblem::CameraBlock block;
    block.camera = &camera;
    if (!constant && config.constant_cameras.count(camera_id) == 0) {
      block.free_params = FreeCameraParamIdxs(options, camera.model_id);
    }
    camera_index.emplace(camera_id, static_cast<int>(problem.cameras.size()));
    problem.cameras.push_back(std::move(block));
  };
  for (const camera_t camera_id : variable_camera_ids) add_camera(camera_id, false);
  for (const camera_t camera_id : outside_camera_ids) add_camera(camera_id, true);

  const auto add_observation = [&](const Image& image, const Eigen::Vector2d& xy, int point) {
    BundleAdjustmentProblem::Observation observation;
    observation.pose = pose_index.at(image.image_id);
    observation.point = point;
    observation.camera = camera_index.at(image.camera_id);
    observation.xy = xy;
    ++problem.poses[observation.pose].num_observations;
    ++problem.cameras[observation.camera].num_observations;
    problem.observations.push_back(observation);
  };
  for (const image_t image_id : config.images) {
    const Image& image = reconstruction->GetImage(image_id);
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D())
        add_observation(image, point2D.xy, point_index.at(point2D.point3D_id));
    }
  }
  for (size_t j = 0; j < point3D_ids.size(); ++j) {
    for (const TrackElement& element : reconstruction->GetPoint3D(point3D_ids[j]).track.elements) {
      // Outside images were posed after the config's.
      const auto pose = pose_index.find(element.image_id);
      if (pose == pose_index.end() || pose->second < static_cast<int>(config.images.size()))
        continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      add_observation(image, image.points2D[element.point2D_idx].xy, static_cast<int>(j));
    }
  }
  for (const BundleAdjustmentProblem::Pose& pose : problem.poses) {
    if (pose.num_observations > 0 && config.images.count(pose.image_id) > 0) {
      ++problem.num_config_images;
    }
  }
  return problem;
}

}  // namespace parallax
