#include "parallax/sfm/point_completion.h"

#include <algorithm>
#include <map>
#include <optional>

#include "parallax/geometry/triangulation.h"

namespace parallax {

size_t CompletePoint(const TrackTriangulationOptions& options, point3D_t point3D_id,
                     TrackedReconstruction* model) {
  // Without hops nothing is reached: returned before the lookups and the copy of the track,
  // which the mapper otherwise paid for every point of every local adjustment (the default).
  if (options.complete_max_transitivity <= 0) return 0;
  const Reconstruction& reconstruction = model->Model();
  if (!reconstruction.ExistsPoint3D(point3D_id)) return 0;
  const Point3D& point = reconstruction.GetPoint3D(point3D_id);
  // Breadth first through the correspondences, as far as the hops allow, through the free
  // keypoints (registered images, no point): they are the candidates. Keypoints of other
  // points are their own points' business (merging), and those of images not registered yet
  // cannot join; walking through either would spread over the whole graph where wrong
  // matches link points.
  // Keypoints of the point itself are not free, so `visited` holds only the others (most
  // correspondences lead back into the point).
  std::vector<TrackElement> frontier = point.track.elements;
  std::vector<TrackElement> visited;
  std::vector<TrackElement> next;
  size_t num_added = 0;
  for (int hop = 0; hop < options.complete_max_transitivity && !frontier.empty(); ++hop) {
    next.clear();
    for (const TrackElement& element : frontier) {
      for (const TrackElement& other :
           model->Graph().CorrespondencesOf(element.image_id, element.point2D_idx)) {
        if (!model->IsFree(other) ||
            std::find(visited.begin(), visited.end(), other) != visited.end()) {
          continue;
        }
        visited.push_back(other);
        next.push_back(other);
        if (point.track.ContainsImage(other.image_id)) continue;
        if (reconstruction.ReprojectionError(other.image_id, other.point2D_idx, point.xyz) <=
            options.max_reprojection_error_px) {
          model->AddObservation(point3D_id, other);
          ++num_added;
        }
      }
    }
    frontier.swap(next);
  }
  return num_added;
}

namespace {

// The observations two points would have as one, the keypoint closer to `xyz` kept where
// both observe an image; empty when one of the kept observations is further off than the
// threshold.
std::vector<TrackElement> MergedObservations(const Reconstruction& reconstruction,
                                             const Point3D& point1, const Point3D& point2,
                                             const Eigen::Vector3d& xyz, double max_error) {
  std::map<image_t, std::pair<double, point2D_t>> best;
  for (const Point3D* point : {&point1, &point2}) {
    for (const TrackElement& element : point->track.elements) {
      const double error =
          reconstruction.ReprojectionError(element.image_id, element.point2D_idx, xyz);
      const auto [it, inserted] = best.try_emplace(element.image_id, error, element.point2D_idx);
      if (!inserted && error < it->second.first) it->second = {error, element.point2D_idx};
    }
  }
  std::vector<TrackElement> elements;
  for (const auto& [image_id, entry] : best) {
    if (!(entry.first <= max_error)) return {};
    elements.push_back({image_id, entry.second});
  }
  return elements;
}

// The point at which the observations of both agree best (multi-view linear triangulation).
std::optional<Eigen::Vector3d> Refit(const Reconstruction& reconstruction, const Point3D& point1,
                                     const Point3D& point2) {
  std::vector<Matrix3x4d> matrices;
  std::vector<Eigen::Vector2d> points;
  for (const Point3D* point : {&point1, &point2}) {
    for (const TrackElement& element : point->track.elements) {
      const Image& image = reconstruction.GetImage(element.image_id);
      matrices.push_back(image.cam_from_world.ToMatrix());
      points.push_back(reconstruction.GetCamera(image.camera_id)
                           .CamFromImg(image.points2D[element.point2D_idx].xy));
    }
  }
  return TriangulateMultiViewPoint(matrices, points);
}

// Replaces the two points by one at `xyz` holding only `elements` (where both observed an
// image, the other keypoint is let go); returns its id.
point3D_t ReplaceByMerged(point3D_t point3D_id1, point3D_t point3D_id2, const Eigen::Vector3d& xyz,
                          const std::vector<TrackElement>& elements, TrackedReconstruction* model) {
  const point3D_t merged = model->MergePoints3D(point3D_id1, point3D_id2);
  Reconstruction& reconstruction = model->Model();
  const std::vector<TrackElement> all = reconstruction.GetPoint3D(merged).track.elements;
  for (const TrackElement& element : all) {
    if (std::find(elements.begin(), elements.end(), element) == elements.end()) {
      reconstruction.DeleteObservation(element.image_id, element.point2D_idx);
    }
  }
  reconstruction.GetPoint3D(merged).xyz = xyz;
  return merged;
}

// The first point that a correspondence of `point3D_id`'s observations links it to and that
// merges with it; kInvalidPoint3DId when none does.
point3D_t MergeOnce(const TrackTriangulationOptions& options, point3D_t point3D_id,
                    TrackedReconstruction* model) {
  const Reconstruction& reconstruction = model->Model();
  const Point3D& point = reconstruction.GetPoint3D(point3D_id);
  std::vector<point3D_t> tried;
  for (const TrackElement& element : point.track.elements) {
    for (const point3D_t other_id : model->PointsOfCorrespondences(element)) {
      if (other_id == point3D_id ||
          std::find(tried.begin(), tried.end(), other_id) != tried.end()) {
        continue;
      }
      tried.push_back(other_id);
      const Point3D& other = reconstruction.GetPoint3D(other_id);
      const std::optional<Eigen::Vector3d> xyz = Refit(reconstruction, point, other);
      if (!xyz) continue;
      const std::vector<TrackElement> elements =
          MergedObservations(reconstruction, point, other, *xyz, options.max_reprojection_error_px);
      if (elements.size() < 2) continue;
      return ReplaceByMerged(point3D_id, other_id, *xyz, elements, model);
    }
  }
  return kInvalidPoint3DId;
}

}  // namespace

size_t MergePoint(const TrackTriangulationOptions& options, point3D_t point3D_id,
                  TrackedReconstruction* model) {
  size_t num_merged = 0;
  while (options.merge_points && model->Model().ExistsPoint3D(point3D_id)) {
    const point3D_t merged = MergeOnce(options, point3D_id, model);
    if (merged == kInvalidPoint3DId) break;
    ++num_merged;
    point3D_id = merged;
  }
  return num_merged;
}

size_t CompleteAndMergePoints(const TrackTriangulationOptions& options,
                              const std::vector<point3D_t>& point3D_ids,
                              TrackedReconstruction* model) {
  size_t num_changed = 0;
  for (const point3D_t point3D_id : point3D_ids) {
    num_changed += CompletePoint(options, point3D_id, model);
  }
  for (const point3D_t point3D_id : point3D_ids) {
    num_changed += MergePoint(options, point3D_id, model);
  }
  return num_changed;
}

size_t CompleteAndMergeAllPoints(const TrackTriangulationOptions& options,
                                 TrackedReconstruction* model) {
  std::vector<point3D_t> point3D_ids;
  point3D_ids.reserve(model->Model().NumPoints3D());
  for (const auto& [point3D_id, point] : model->Model().Points3D()) {
    point3D_ids.push_back(point3D_id);
  }
  return CompleteAndMergePoints(options, point3D_ids, model);
}

}  // namespace parallax
