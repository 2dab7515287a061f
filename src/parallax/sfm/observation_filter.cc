#include "parallax/sfm/observation_filter.h"

#include <cmath>
#include <unordered_map>

#include "parallax/geometry/triangulation.h"
#include "parallax/util/check.h"

namespace parallax {

void ObservationFilterOptions::Check() const {
  PARALLAX_CHECK_GT(max_reprojection_error_px, 0.0);
  PARALLAX_CHECK_GE(min_triangulation_angle_deg, 0.0);
}

namespace {

// An image's pose, camera and centre, found once per filtering: the mapper filters the points
// of its local adjustment after each, and looking up image and camera in the model's trees and
// the centre for every observation took most of the filter's time.
struct ImageView {
  const Image* image = nullptr;
  const Camera* camera = nullptr;
  Eigen::Vector3d centre;
};

class ImageViews {
 public:
  explicit ImageViews(const Reconstruction& reconstruction) : reconstruction_(reconstruction) {}

  const ImageView& Get(image_t image_id) {
    const auto [it, inserted] = views_.try_emplace(image_id);
    if (inserted) {
      const Image& image = reconstruction_.GetImage(image_id);
      it->second = {&image, &reconstruction_.GetCamera(image.camera_id), image.ProjectionCenter()};
    }
    return it->second;
  }

 private:
  const Reconstruction& reconstruction_;
  std::unordered_map<image_t, ImageView> views_;
};

}  // namespace

size_t FilterPoints(const ObservationFilterOptions& options,
                    const std::vector<point3D_t>& point3D_ids, Reconstruction* reconstruction) {
  options.Check();
  const double min_angle = options.min_triangulation_angle_deg * M_PI / 180.0;
  size_t num_removed = 0;
  std::vector<TrackElement> bad;
  std::vector<Eigen::Vector3d> centers;
  // Filtering edits tracks only: poses, cameras and the maps' nodes stay where they are.
  ImageViews views(*reconstruction);
  for (const point3D_t point3D_id : point3D_ids) {
    if (!reconstruction->ExistsPoint3D(point3D_id)) continue;
    const Point3D& point = reconstruction->GetPoint3D(point3D_id);
    bad.clear();
    for (const TrackElement& element : point.track.elements) {
      const ImageView& view = views.Get(element.image_id);
      const double error =
          ReprojectionError(*view.image, *view.camera, element.point2D_idx, point.xyz);
      if (!(error <= options.max_reprojection_error_px)) bad.push_back(element);
    }
    const size_t track_length = point.track.Length();
    if (bad.size() + 1 >= track_length) {
      // Fewer than two good observations would remain.
      reconstruction->DeletePoint3D(point3D_id);
      num_removed += track_length;
      continue;
    }
    for (const TrackElement& element : bad) {
      reconstruction->DeleteObservation(element.image_id, element.point2D_idx);
    }
    num_removed += bad.size();

    const Point3D& kept = reconstruction->GetPoint3D(point3D_id);
    double max_angle = 0;
    centers.clear();
    for (const TrackElement& element : kept.track.elements) {
      centers.push_back(views.Get(element.image_id).centre);
    }
    for (size_t a = 0; a < centers.size() && max_angle < min_angle; ++a) {
      for (size_t b = a + 1; b < centers.size() && max_angle < min_angle; ++b) {
        max_angle =
            std::max(max_angle, CalculateTriangulationAngle(centers[a], centers[b], kept.xyz));
      }
    }
    if (max_angle < min_angle) {
      num_removed += kept.track.Length();
      reconstruction->DeletePoint3D(point3D_id);
    }
  }
  return num_removed;
}

size_t FilterAllPoints(const ObservationFilterOptions& options, Reconstruction* reconstruction) {
  std::vector<point3D_t> ids;
  ids.reserve(reconstruction->NumPoints3D());
  for (const auto& [point3D_id, point] : reconstruction->Points3D()) ids.push_back(point3D_id);
  return FilterPoints(options, ids, reconstruction);
}

}  // namespace parallax
