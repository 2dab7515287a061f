#include "parallax/sfm/observation_filter.h"

#include <cmath>

#include "parallax/geometry/triangulation.h"
#include "parallax/util/check.h"

namespace parallax {

void ObservationFilterOptions::Check() const {
  PARALLAX_CHECK_GT(max_reprojection_error_px, 0.0);
  PARALLAX_CHECK_GE(min_triangulation_angle_deg, 0.0);
}

size_t FilterPoints(const ObservationFilterOptions& options,
                    const std::vector<point3D_t>& point3D_ids, Reconstruction* reconstruction) {
  options.Check();
  const double min_angle = options.min_triangulation_angle_deg * M_PI / 180.0;
  size_t num_removed = 0;
  std::vector<TrackElement> bad;
  for (const point3D_t point3D_id : point3D_ids) {
    if (!reconstruction->ExistsPoint3D(point3D_id)) continue;
    const Point3D& point = reconstruction->GetPoint3D(point3D_id);
    bad.clear();
    for (const TrackElement& element : point.track.elements) {
      const double error =
          reconstruction->ReprojectionError(element.image_id, element.point2D_idx, point.xyz);
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
    std::vector<Eigen::Vector3d> centers;
    for (const TrackElement& element : kept.track.elements) {
      centers.push_back(reconstruction->GetImage(element.image_id).ProjectionCenter());
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
