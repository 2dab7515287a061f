#include "parallax/estimators/bundle_adjustment_problem.h"

#include <algorithm>
#include <map>
#include <set>
#include <unordered_map>

#include "parallax/util/check.h"
#include "parallax/util/types.h"

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

  // Images in flat tables by slot: the mapper gathers a problem around every new image, and
  // tree and hash lookups per observation were a twentieth of its time. The slot is the id
  // where ids fit a flat table (always, from the mapper), else the image's rank.
  const std::map<image_t, Image>& images = reconstruction->Images();
  const size_t max_id = images.empty() ? 0 : static_cast<size_t>(images.rbegin()->first);
  const bool dense_ids = IdsFitFlatTable(max_id, images.size());
  const size_t num_slots = dense_ids ? max_id + 1 : images.size();
  std::unordered_map<image_t, size_t> rank_of_id;
  std::vector<Image*> image_in_slot(num_slots, nullptr);
  for (const auto& [image_id, image] : images) {
    const size_t slot = dense_ids ? image_id : rank_of_id.size();
    if (!dense_ids) rank_of_id.emplace(image_id, slot);
    image_in_slot[slot] = &reconstruction->GetImage(image_id);
  }
  const auto slot_of = [&](image_t image_id) {
    size_t slot = num_slots;
    if (dense_ids) {
      slot = image_id;
    } else if (const auto it = rank_of_id.find(image_id); it != rank_of_id.end()) {
      slot = it->second;
    }
    PARALLAX_CHECK_MSG(slot < num_slots && image_in_slot[slot] != nullptr, "no image " << image_id);
    return slot;
  };
  // Problem pose of each slot's image (-1: none yet).
  std::vector<int> pose_of_slot(num_slots, -1);

  // The config's images and cameras, the points they observe, and those points' other
  // registered views (constant poses, as COLMAP does), each in id order.
  std::set<camera_t> variable_camera_ids;
  std::vector<point3D_t> point3D_ids;
  for (const image_t image_id : config.images) {
    const Image& image = *image_in_slot[slot_of(image_id)];
    variable_camera_ids.insert(image.camera_id);
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D()) point3D_ids.push_back(point2D.point3D_id);
    }
  }
  std::sort(point3D_ids.begin(), point3D_ids.end());
  point3D_ids.erase(std::unique(point3D_ids.begin(), point3D_ids.end()), point3D_ids.end());
  std::vector<char> in_config(num_slots, 0);
  for (const image_t image_id : config.images) in_config[slot_of(image_id)] = 1;
  std::vector<char> is_outside(num_slots, 0);
  std::set<camera_t> outside_camera_ids;
  for (const point3D_t point3D_id : point3D_ids) {
    for (const TrackElement& element : reconstruction->GetPoint3D(point3D_id).track.elements) {
      const size_t slot = slot_of(element.image_id);
      const Image& image = *image_in_slot[slot];
      if (in_config[slot] || is_outside[slot] || !image.registered) continue;
      is_outside[slot] = 1;
      if (variable_camera_ids.count(image.camera_id) == 0) {
        outside_camera_ids.insert(image.camera_id);
      }
    }
  }

  // Points in id order, each id's problem index in a hash table: a binary search in
  // point3D_ids per observation, its branches mispredicted, was half of this function.
  std::unordered_map<point3D_t, int> index_of_point;
  index_of_point.reserve(point3D_ids.size());
  for (const point3D_t point3D_id : point3D_ids) {
    index_of_point.emplace(point3D_id, static_cast<int>(problem.points.size()));
    problem.points.push_back({&reconstruction->GetPoint3D(point3D_id).xyz,
                              config.constant_points.count(point3D_id) > 0});
  }
  const auto point_index = [&](point3D_t point3D_id) {
    const auto it = index_of_point.find(point3D_id);
    PARALLAX_CHECK(it != index_of_point.end());
    return it->second;
  };
  const auto add_pose = [&](image_t image_id, bool constant) {
    BundleAdjustmentProblem::Pose pose;
    pose.image_id = image_id;
    const size_t slot = slot_of(image_id);
    pose.cam_from_world = &image_in_slot[slot]->cam_from_world;
    pose.constant = constant || config.constant_poses.count(image_id) > 0;
    for (int c = 0; c < 3; ++c) {
      pose.constant_translation[c] =
          config.constant_translation_coordinates.count({image_id, c}) > 0;
    }
    pose_of_slot[slot] = static_cast<int>(problem.poses.size());
    problem.poses.push_back(pose);
  };
  for (const image_t image_id : config.images) add_pose(image_id, false);
  for (size_t slot = 0; slot < num_slots; ++slot) {  // Slots are in id order.
    if (is_outside[slot]) add_pose(image_in_slot[slot]->image_id, true);
  }
  std::map<camera_t, int> camera_index;
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
  // Problem camera of each pose.
  std::vector<int> camera_of_pose(problem.poses.size());
  for (size_t i = 0; i < problem.poses.size(); ++i) {
    camera_of_pose[i] =
        camera_index.at(image_in_slot[slot_of(problem.poses[i].image_id)]->camera_id);
  }

  const auto add_observation = [&](int pose, const Eigen::Vector2d& xy, int point) {
    BundleAdjustmentProblem::Observation observation;
    observation.pose = pose;
    observation.point = point;
    observation.camera = camera_of_pose[pose];
    observation.xy = xy;
    ++problem.poses[observation.pose].num_observations;
    ++problem.cameras[observation.camera].num_observations;
    problem.observations.push_back(observation);
  };
  for (const image_t image_id : config.images) {
    const size_t slot = slot_of(image_id);
    const Image& image = *image_in_slot[slot];
    const int pose = pose_of_slot[slot];
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D()) add_observation(pose, point2D.xy, point_index(point2D.point3D_id));
    }
  }
  for (size_t j = 0; j < point3D_ids.size(); ++j) {
    for (const TrackElement& element : reconstruction->GetPoint3D(point3D_ids[j]).track.elements) {
      // Outside images were posed after the config's.
      const size_t slot = slot_of(element.image_id);
      const int pose = pose_of_slot[slot];
      if (pose < static_cast<int>(config.images.size())) continue;
      add_observation(pose, image_in_slot[slot]->points2D[element.point2D_idx].xy,
                      static_cast<int>(j));
    }
  }
  for (size_t i = 0; i < config.images.size(); ++i) {  // The config's poses come first.
    if (problem.poses[i].num_observations > 0) ++problem.num_config_images;
  }
  return problem;
}

}  // namespace parallax
