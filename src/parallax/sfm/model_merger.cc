#include "parallax/sfm/model_merger.h"

#include <algorithm>
#include <unordered_map>

#include "parallax/estimators/similarity_transform.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {

void ModelMergerOptions::Check() const {
  PARALLAX_CHECK_GE(min_shared_images, 1);
  PARALLAX_CHECK_GE(min_inlier_points, 3);
  PARALLAX_CHECK_GT(max_error_fraction, 0.0);
  ransac.Check();
}

namespace {

uint64_t ObservationKey(image_t image_id, point2D_t point2D_idx) {
  return (static_cast<uint64_t>(image_id) << 32) | point2D_idx;
}

// Where each observed keypoint of the merged images lies in the merged frame: the point of
// the model that brought the image in, so that a later model finds its counterpart.
class MergedObservations {
 public:
  // Records the observations of `model`'s points in `image_ids`, mapped by merged_from_model;
  // keypoints already recorded keep their point.
  void Add(const Reconstruction& model, const std::vector<image_t>& image_ids,
           const Sim3d& merged_from_model) {
    for (const image_t image_id : image_ids) {
      const Image& image = model.GetImage(image_id);
      for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
        const Point2D& point2D = image.points2D[idx];
        if (!point2D.HasPoint3D()) continue;
        xyz_.emplace(ObservationKey(image_id, idx),
                     merged_from_model * model.GetPoint3D(point2D.point3D_id).xyz);
      }
    }
  }

  // Pairs (point in model, point in merged frame) seen by the same keypoint of a shared
  // image, one per point of the model.
  void Correspondences(const Reconstruction& model, const std::vector<image_t>& shared_images,
                       std::vector<Eigen::Vector3d>* model_points,
                       std::vector<Eigen::Vector3d>* merged_points) const {
    std::unordered_map<point3D_t, bool> used;
    for (const image_t image_id : shared_images) {
      const Image& image = model.GetImage(image_id);
      for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
        const Point2D& point2D = image.points2D[idx];
        if (!point2D.HasPoint3D()) continue;
        const auto it = xyz_.find(ObservationKey(image_id, idx));
        if (it == xyz_.end() || !used.emplace(point2D.point3D_id, true).second) continue;
        model_points->push_back(model.GetPoint3D(point2D.point3D_id).xyz);
        merged_points->push_back(it->second);
      }
    }
  }

 private:
  std::unordered_map<uint64_t, Eigen::Vector3d> xyz_;
};

std::vector<image_t> SharedImages(const Reconstruction& model, const Reconstruction& merged) {
  std::vector<image_t> shared;
  for (const image_t image_id : model.RegImageIds()) {
    if (merged.ExistsImage(image_id)) shared.push_back(image_id);
  }
  return shared;
}

ModelMergeReport EstimateMergedFromModel(const ModelMergerOptions& options,
                                         const Reconstruction& model,
                                         const std::vector<image_t>& shared_images,
                                         const MergedObservations& observations) {
  ModelMergeReport report;
  report.num_shared_images = shared_images.size();
  std::vector<Eigen::Vector3d> model_points, merged_points;
  observations.Correspondences(model, shared_images, &model_points, &merged_points);
  report.num_correspondences = model_points.size();
  if (static_cast<int>(model_points.size()) < options.min_inlier_points) return report;
  RansacOptions ransac_options = options.ransac;
  ransac_options.random_seed = options.seed;
  ransac_options.max_error = options.max_error_fraction * MedianDistanceFromMedian(merged_points);
  const Sim3dRansacReport sim3 = EstimateSim3dRansac(model_points, merged_points, ransac_options);
  report.num_inliers = sim3.num_inliers;
  report.merged_from_model = sim3.dst_from_src;
  report.success = sim3.success && static_cast<int>(sim3.num_inliers) >= options.min_inlier_points;
  return report;
}

}  // namespace

void AddPoseOnlyImage(const Reconstruction& model, image_t image_id, const Sim3d& into_from_model,
                      Reconstruction* into) {
  const Image& image = model.GetImage(image_id);
  Image pose_only;
  pose_only.image_id = image_id;
  pose_only.camera_id = image.camera_id;
  pose_only.name = image.name;
  pose_only.cam_from_world = TransformCameraPose(into_from_model, image.cam_from_world);
  into->AddImage(pose_only);
  into->RegisterImage(image_id);
}

double MedianDistanceFromMedian(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d median;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    for (const Eigen::Vector3d& point : points) values.push_back(point[axis]);
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    median[axis] = values[values.size() / 2];
  }
  std::vector<double> distances;
  for (const Eigen::Vector3d& point : points) distances.push_back((point - median).norm());
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
  return distances[distances.size() / 2];
}

Reconstruction MergeModels(const ModelMergerOptions& options,
                           const std::vector<Reconstruction>& models,
                           std::vector<ModelMergeReport>* reports) {
  options.Check();
  std::vector<ModelMergeReport> merge_reports(models.size());
  Reconstruction merged;
  if (models.empty()) {
    if (reports != nullptr) *reports = merge_reports;
    return merged;
  }
  MergedObservations observations;
  const auto add_model = [&](size_t index, const Sim3d& merged_from_model) {
    const Reconstruction& model = models[index];
    std::vector<image_t> added;
    for (const auto& [camera_id, camera] : model.Cameras()) {
      if (!merged.ExistsCamera(camera_id)) merged.AddCamera(camera);
    }
    for (const image_t image_id : model.RegImageIds()) {
      if (merged.ExistsImage(image_id)) continue;
      AddPoseOnlyImage(model, image_id, merged_from_model, &merged);
      added.push_back(image_id);
    }
    observations.Add(model, added, merged_from_model);
  };

  size_t largest = 0;
  for (size_t index = 1; index < models.size(); ++index) {
    if (models[index].NumRegImages() > models[largest].NumRegImages()) largest = index;
  }
  add_model(largest, Sim3d());
  merge_reports[largest].success = true;
  std::vector<bool> done(models.size(), false);
  done[largest] = true;
  while (true) {
    // The model sharing the most images; ties to the lower index.
    size_t best = models.size();
    std::vector<image_t> best_shared;
    for (size_t index = 0; index < models.size(); ++index) {
      if (done[index]) continue;
      std::vector<image_t> shared = SharedImages(models[index], merged);
      if (shared.size() > best_shared.size()) {
        best = index;
        best_shared = std::move(shared);
      }
    }
    if (best == models.size() || static_cast<int>(best_shared.size()) < options.min_shared_images)
      break;
    done[best] = true;
    merge_reports[best] = EstimateMergedFromModel(options, models[best], best_shared, observations);
    const ModelMergeReport& report = merge_reports[best];
    PARALLAX_LOG(Debug) << "merge: model " << best << " (" << models[best].NumRegImages()
                        << " images) shares " << report.num_shared_images << " images, "
                        << report.num_inliers << "/" << report.num_correspondences
                        << " points agree" << (report.success ? "" : ": left out");
    if (report.success) add_model(best, report.merged_from_model);
  }
  if (reports != nullptr) *reports = merge_reports;
  return merged;
}

}  // namespace parallax
