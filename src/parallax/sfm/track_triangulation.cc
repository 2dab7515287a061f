#include "parallax/sfm/track_triangulation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallax/geometry/triangulation.h"
#include "parallax/util/check.h"

namespace parallax {

void TrackTriangulationOptions::Check() const {
  PARALLAX_CHECK_GE(min_angle_deg, 0.0);
  PARALLAX_CHECK_GT(max_reprojection_error_px, 0.0);
  PARALLAX_CHECK_GE(max_pair_trials, 1);
}

namespace {

constexpr double kDegToRad = M_PI / 180.0;

struct View {
  TrackElement element;
  Matrix3x4d cam_from_world;
  Eigen::Vector3d center;
  Eigen::Vector2d normalized;
};

// Views of the track whose image is registered and whose keypoint has no point yet.
std::vector<View> CollectViews(track_t track_id, const TrackedReconstruction& model) {
  std::vector<View> views;
  const Reconstruction& reconstruction = model.Model();
  for (const TrackElement& element : model.Graph().TrackElements(track_id)) {
    if (!reconstruction.ExistsImage(element.image_id)) continue;
    const Image& image = reconstruction.GetImage(element.image_id);
    if (!image.registered || image.points2D[element.point2D_idx].HasPoint3D()) continue;
    View view;
    view.element = element;
    view.cam_from_world = image.cam_from_world.ToMatrix();
    view.center = image.ProjectionCenter();
    view.normalized = reconstruction.GetCamera(image.camera_id)
                          .CamFromImg(image.points2D[element.point2D_idx].xy);
    views.push_back(view);
  }
  return views;
}

// Views that agree with a point: in front and within the reprojection threshold.
std::vector<size_t> AgreeingViews(const std::vector<View>& views, const Eigen::Vector3d& xyz,
                                  const Reconstruction& reconstruction, double max_error,
                                  double* error_sum) {
  std::vector<size_t> agreeing;
  *error_sum = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const double error = reconstruction.ReprojectionError(views[i].element.image_id,
                                                          views[i].element.point2D_idx, xyz);
    if (error <= max_error) {
      agreeing.push_back(i);
      *error_sum += error;
    }
  }
  return agreeing;
}

double MaxAngle(const std::vector<View>& views, const std::vector<size_t>& subset,
                const Eigen::Vector3d& xyz) {
  double max_angle = 0;
  for (size_t a = 0; a < subset.size(); ++a) {
    for (size_t b = a + 1; b < subset.size(); ++b) {
      max_angle = std::max(max_angle, CalculateTriangulationAngle(views[subset[a]].center,
                                                                  views[subset[b]].center, xyz));
    }
  }
  return max_angle;
}

}  // namespace

point3D_t TriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                           TrackedReconstruction* model) {
  if (model->PointOfTrack(track_id) != kInvalidPoint3DId) return kInvalidPoint3DId;
  const std::vector<View> views = CollectViews(track_id, *model);
  if (views.size() < 2) return kInvalidPoint3DId;
  Reconstruction& reconstruction = model->Model();
  const double min_angle = options.min_angle_deg * kDegToRad;

  // Hypotheses from view pairs: all pairs for short tracks, an even spread for long ones.
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t a = 0; a < views.size(); ++a) {
    for (size_t b = a + 1; b < views.size(); ++b) pairs.emplace_back(a, b);
  }
  if (pairs.size() > static_cast<size_t>(options.max_pair_trials)) {
    std::vector<std::pair<size_t, size_t>> spread;
    const double step = static_cast<double>(pairs.size()) / options.max_pair_trials;
    for (int i = 0; i < options.max_pair_trials; ++i) {
      spread.push_back(pairs[static_cast<size_t>(i * step)]);
    }
    pairs.swap(spread);
  }

  std::vector<size_t> best_views;
  double best_error = std::numeric_limits<double>::max();
  for (const auto& [a, b] : pairs) {
    const auto xyz = TriangulatePoint(views[a].cam_from_world, views[b].cam_from_world,
                                      views[a].normalized, views[b].normalized);
    if (!xyz) continue;
    if (CalculateTriangulationAngle(views[a].center, views[b].center, *xyz) < min_angle) continue;
    double error_sum = 0;
    std::vector<size_t> agreeing =
        AgreeingViews(views, *xyz, reconstruction, options.max_reprojection_error_px, &error_sum);
    if (agreeing.size() > best_views.size() ||
        (agreeing.size() == best_views.size() && error_sum < best_error)) {
      best_views = std::move(agreeing);
      best_error = error_sum;
    }
    if (best_views.size() == views.size()) break;
  }
  if (best_views.size() < 2) return kInvalidPoint3DId;

  std::vector<Matrix3x4d> matrices;
  std::vector<Eigen::Vector2d> points;
  for (size_t i : best_views) {
    matrices.push_back(views[i].cam_from_world);
    points.push_back(views[i].normalized);
  }
  const auto refined = TriangulateMultiViewPoint(matrices, points);
  if (!refined) return kInvalidPoint3DId;
  double error_sum = 0;
  const std::vector<size_t> final_views =
      AgreeingViews(views, *refined, reconstruction, options.max_reprojection_error_px, &error_sum);
  if (final_views.size() < 2 || MaxAngle(views, final_views, *refined) < min_angle) {
    return kInvalidPoint3DId;
  }
  Track track;
  for (size_t i : final_views) track.elements.push_back(views[i].element);
  const point3D_t point3D_id = reconstruction.AddPoint3D(*refined, std::move(track));
  model->SetPointOfTrack(track_id, point3D_id);
  return point3D_id;
}

size_t ContinueTrack(const TrackTriangulationOptions& options, track_t track_id,
                     TrackedReconstruction* model) {
  const point3D_t point3D_id = model->PointOfTrack(track_id);
  if (point3D_id == kInvalidPoint3DId) return 0;
  Reconstruction& reconstruction = model->Model();
  const Eigen::Vector3d xyz = reconstruction.GetPoint3D(point3D_id).xyz;
  size_t num_added = 0;
  for (const TrackElement& element : model->Graph().TrackElements(track_id)) {
    if (!reconstruction.ExistsImage(element.image_id)) continue;
    const Image& image = reconstruction.GetImage(element.image_id);
    if (!image.registered || image.points2D[element.point2D_idx].HasPoint3D()) continue;
    if (reconstruction.ReprojectionError(element.image_id, element.point2D_idx, xyz) <=
        options.max_reprojection_error_px) {
      reconstruction.AddObservation(point3D_id, element);
      ++num_added;
    }
  }
  return num_added;
}

size_t ContinueOrTriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                                  TrackedReconstruction* model) {
  if (model->PointOfTrack(track_id) != kInvalidPoint3DId)
    return ContinueTrack(options, track_id, model);
  const point3D_t point3D_id = TriangulateTrack(options, track_id, model);
  return point3D_id == kInvalidPoint3DId ? 0 : model->Model().GetPoint3D(point3D_id).track.Length();
}

size_t TriangulateImage(const TrackTriangulationOptions& options, image_t image_id,
                        TrackedReconstruction* model) {
  const Image& image = model->Model().GetImage(image_id);
  const track_t* tracks = model->Graph().TracksOfImage(image_id);
  size_t num_added = 0;
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    const track_t track_id = tracks[idx];
    if (track_id != kInvalidTrackId)
      num_added += ContinueOrTriangulateTrack(options, track_id, model);
  }
  return num_added;
}

size_t CompleteAllTracks(const TrackTriangulationOptions& options, TrackedReconstruction* model) {
  size_t num_added = 0;
  for (track_t track_id = 0; track_id < model->Graph().NumTracks(); ++track_id) {
    num_added += ContinueOrTriangulateTrack(options, track_id, model);
  }
  return num_added;
}

}  // namespace parallax
