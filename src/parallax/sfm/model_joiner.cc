#include "parallax/sfm/model_joiner.h"

#include <unordered_map>

#include "parallax/sfm/model_merger.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {

void ModelJoinerOptions::Check() const {
  PARALLAX_CHECK_GE(min_inlier_points, 3);
  PARALLAX_CHECK_GT(max_error_fraction, 0.0);
  ransac.Check();
}

namespace {

// Each track's point in the model: the one with the most observations where the track's
// keypoints went to several.
std::unordered_map<track_t, point3D_t> PointOfTrack(const Reconstruction& model,
                                                    const CorrespondenceGraph& graph) {
  std::unordered_map<track_t, point3D_t> point_of_track;
  for (const image_t image_id : model.RegImageIds()) {
    if (!graph.ExistsImage(image_id)) continue;
    const Image& image = model.GetImage(image_id);
    const track_t* tracks = graph.TracksOfImage(image_id);
    for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
      const point3D_t point3D_id = image.points2D[idx].point3D_id;
      if (point3D_id == kInvalidPoint3DId || tracks[idx] == kInvalidTrackId) continue;
      const auto [it, inserted] = point_of_track.try_emplace(tracks[idx], point3D_id);
      if (!inserted && model.GetPoint3D(point3D_id).track.Length() >
                           model.GetPoint3D(it->second).track.Length()) {
        it->second = point3D_id;
      }
    }
  }
  return point_of_track;
}

}  // namespace

Reconstruction JoinModels(const ModelJoinerOptions& options,
                          const std::vector<Reconstruction>& models,
                          const CorrespondenceGraph& correspondence_graph,
                          std::vector<ModelJoinReport>* reports) {
  options.Check();
  PARALLAX_CHECK(reports != nullptr);
  *reports = std::vector<ModelJoinReport>(models.size());
  Reconstruction joined;
  if (models.empty()) return joined;
  std::vector<std::unordered_map<track_t, point3D_t>> points(models.size());
  for (size_t index = 0; index < models.size(); ++index) {
    points[index] = PointOfTrack(models[index], correspondence_graph);
  }
  std::unordered_map<track_t, Eigen::Vector3d> joined_xyz;  // Each joined track, in the frame.
  const auto add_model = [&](size_t index, const Sim3d& joined_from_model) {
    const Reconstruction& model = models[index];
    for (const auto& [camera_id, camera] : model.Cameras()) {
      if (!joined.ExistsCamera(camera_id)) joined.AddCamera(camera);
    }
    for (const image_t image_id : model.RegImageIds()) {
      AddPoseOnlyImage(model, image_id, joined_from_model, &joined);
    }
    for (const auto& [track_id, point3D_id] : points[index]) {
      joined_xyz.try_emplace(track_id, joined_from_model * model.GetPoint3D(point3D_id).xyz);
    }
    (*reports)[index].joined = true;
    (*reports)[index].joined_from_model = joined_from_model;
  };

  size_t largest = 0;
  for (size_t index = 1; index < models.size(); ++index) {
    if (models[index].NumRegImages() > models[largest].NumRegImages()) largest = index;
  }
  add_model(largest, Sim3d());
  std::vector<bool> tried(models.size(), false);
  tried[largest] = true;
  while (true) {
    // The model sharing the most tracks with the joined ones; ties to the lower index.
    size_t best = models.size();
    std::vector<Eigen::Vector3d> best_model_points, best_joined_points;
    for (size_t index = 0; index < models.size(); ++index) {
      if (tried[index]) continue;
      std::vector<Eigen::Vector3d> model_points, joined_points;
      for (const auto& [track_id, point3D_id] : points[index]) {
        const auto it = joined_xyz.find(track_id);
        if (it == joined_xyz.end()) continue;
        model_points.push_back(models[index].GetPoint3D(point3D_id).xyz);
        joined_points.push_back(it->second);
      }
      (*reports)[index].num_shared_tracks = model_points.size();
      if (model_points.size() > best_model_points.size()) {
        best = index;
        best_model_points = std::move(model_points);
        best_joined_points = std::move(joined_points);
      }
    }
    if (best == models.size() ||
        static_cast<int>(best_model_points.size()) < options.min_inlier_points) {
      break;
    }
    tried[best] = true;
    RansacOptions ransac_options = options.ransac;
    ransac_options.random_seed = options.seed + best;
    ransac_options.max_error =
        options.max_error_fraction * MedianDistanceFromMedian(best_joined_points);
    const Sim3dRansacReport sim3 =
        EstimateSim3dRansac(best_model_points, best_joined_points, ransac_options);
    ModelJoinReport& report = (*reports)[best];
    report.num_inliers = sim3.success ? sim3.num_inliers : 0;
    const bool agrees =
        sim3.success && static_cast<int>(sim3.num_inliers) >= options.min_inlier_points;
    PARALLAX_LOG(Info) << "mapper: model of " << models[best].NumRegImages() << " images shares "
                       << report.num_shared_tracks << " tracks with the joined ones, "
                       << report.num_inliers << " agree" << (agrees ? ": joined" : ": left apart");
    if (agrees) add_model(best, sim3.dst_from_src);
  }
  return joined;
}

}  // namespace parallax
