#include "parallax/report/model_union.h"

#include <algorithm>
#include <map>
#include <set>
#include <string>

#include "parallax/report/ground_truth.h"

namespace parallax {

Reconstruction UniteModels(const Reconstruction& base, const std::string& base_source,
                           const Reconstruction& model, ModelUnionReport* report) {
  EvaluationMetrics alignment;
  const Reconstruction moved =
      AlignToReference(model, GroundTruthOfModel(base, base_source), &alignment);
  Reconstruction united = base;
  std::map<std::string, image_t> base_ids;
  image_t next_image_id = 1;
  camera_t next_camera_id = 1;
  for (const auto& [image_id, image] : base.Images()) {
    base_ids[image.name] = image_id;
    next_image_id = std::max(next_image_id, image_id + 1);
  }
  for (const auto& [camera_id, camera] : base.Cameras()) {
    next_camera_id = std::max(next_camera_id, camera_id + 1);
  }
  ModelUnionReport counts;
  counts.num_alignment_inliers = alignment.num_alignment_inliers;
  counts.scale = alignment.gt_from_model.scale;
  // The images only `model` has, under new ids, without their points (added below).
  std::map<camera_t, camera_t> camera_ids;
  std::map<image_t, image_t> added_ids;
  std::set<image_t> observable;  // Added images whose keypoints are `model`'s.
  for (const image_t image_id : moved.RegImageIds()) {
    const Image& image = moved.GetImage(image_id);
    const auto in_base = base_ids.find(image.name);
    if (in_base != base_ids.end() && base.IsImageRegistered(in_base->second)) {
      ++counts.num_shared_images;
      continue;
    }
    if (in_base != base_ids.end()) {
      // Known to `base` but not registered there: it takes the pose, and the points when the
      // keypoints are the same (one database).
      Image& known = united.GetImage(in_base->second);
      known.cam_from_world = image.cam_from_world;
      united.RegisterImage(known.image_id);
      added_ids[image_id] = known.image_id;
      if (known.points2D.size() == image.points2D.size()) observable.insert(known.image_id);
      ++counts.num_images_added;
      continue;
    }
    if (!camera_ids.count(image.camera_id)) {
      Camera camera = moved.GetCamera(image.camera_id);
      camera.camera_id = next_camera_id++;
      camera_ids[image.camera_id] = camera.camera_id;
      united.AddCamera(camera);
    }
    Image copy = image;
    copy.image_id = next_image_id++;
    copy.camera_id = camera_ids.at(image.camera_id);
    for (Point2D& point2D : copy.points2D) point2D.point3D_id = kInvalidPoint3DId;
    added_ids[image_id] = copy.image_id;
    observable.insert(copy.image_id);
    united.AddImage(copy);
    united.RegisterImage(copy.image_id);
    ++counts.num_images_added;
  }
  for (const auto& [point3D_id, point] : moved.Points3D()) {
    Track track;
    for (const TrackElement& element : point.track.elements) {
      const auto added = added_ids.find(element.image_id);
      if (added == added_ids.end() || !observable.count(added->second)) continue;
      if (united.GetImage(added->second).points2D[element.point2D_idx].HasPoint3D()) continue;
      track.AddElement(added->second, element.point2D_idx);
    }
    if (track.Length() < 2) continue;
    united.AddPoint3D(point.xyz, track, point.color);
    ++counts.num_points_added;
  }
  united.UpdatePointErrors();
  if (report != nullptr) *report = counts;
  return united;
}

}  // namespace parallax
