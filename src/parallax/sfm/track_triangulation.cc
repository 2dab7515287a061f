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
  PARALLAX_CHECK_GE(complete_max_transitivity, 0);
  PARALLAX_CHECK(retriangulate_min_ratio >= 0 && retriangulate_min_ratio <= 1);
  PARALLAX_CHECK_GE(retriangulate_min_angle_deg, 0.0);
  PARALLAX_CHECK_GT(retriangulate_max_reprojection_error_px, 0.0);
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
    if (!model.IsFree(element)) continue;
    const Image& image = reconstruction.GetImage(element.image_id);
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
  if (options.ignore_two_view_tracks && model->Graph().IsTwoViewTrack(track_id)) {
    return kInvalidPoint3DId;
  }
  const std::vector<View> views = CollectViews(track_id, *model);
  if (views.size() < 2) return kInvalidPoint3DId;
  const Reconstruction& reconstruction = model->Model();
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
  return model->AddPoint3D(*refined, std::move(track));
}

point3D_t ContinueKeypoint(const TrackTriangulationOptions& options, const TrackElement& element,
                           const std::vector<point3D_t>& candidates, TrackedReconstruction* model) {
  std::vector<point3D_t> point3D_ids = model->PointsOfCorrespondences(element);
  point3D_ids.insert(point3D_ids.end(), candidates.begin(), candidates.end());
  const Reconstruction& reconstruction = model->Model();
  point3D_t best = kInvalidPoint3DId;
  double best_error = options.max_reprojection_error_px;
  for (const point3D_t point3D_id : point3D_ids) {
    if (!reconstruction.ExistsPoint3D(point3D_id)) continue;
    const Point3D& point = reconstruction.GetPoint3D(point3D_id);
    const double error =
        reconstruction.ReprojectionError(element.image_id, element.point2D_idx, point.xyz);
    // One observation per image: a point seen there already is another keypoint's.
    if (error <= best_error && !point.track.ContainsImage(element.image_id)) {
      best = point3D_id;
      best_error = error;
    }
  }
  if (best != kInvalidPoint3DId) model->AddObservation(best, element);
  return best;
}

size_t ContinueTrack(const TrackTriangulationOptions& options, track_t track_id,
                     TrackedReconstruction* model) {
  std::vector<point3D_t> track_points;
  bool listed = false;
  size_t num_added = 0;
  for (const TrackElement& element : model->Graph().TrackElements(track_id)) {
    if (!model->IsFree(element)) continue;
    if (!listed) {  // Only tracks with a free element pay for the walk.
      track_points = model->PointsOfTrack(track_id);
      listed = true;
    }
    const point3D_t point3D_id = ContinueKeypoint(options, element, track_points, model);
    if (point3D_id != kInvalidPoint3DId) {
      ++num_added;
      // A point new to the track (from a correspondence) is a candidate for the rest.
      if (std::find(track_points.begin(), track_points.end(), point3D_id) == track_points.end()) {
        track_points.push_back(point3D_id);
      }
    }
  }
  return num_added;
}

size_t ContinueOrTriangulateTrack(const TrackTriangulationOptions& options, track_t track_id,
                                  TrackedReconstruction* model) {
  size_t num_added = ContinueTrack(options, track_id, model);
  const point3D_t point3D_id = TriangulateTrack(options, track_id, model);
  if (point3D_id != kInvalidPoint3DId) {
    num_added += model->Model().GetPoint3D(point3D_id).track.Length();
  }
  return num_added;
}

size_t TriangulateImage(const TrackTriangulationOptions& options, image_t image_id,
                        TrackedReconstruction* model) {
  const size_t num_points2D = model->Model().GetImage(image_id).points2D.size();
  const track_t* tracks = model->Graph().TracksOfImage(image_id);
  size_t num_added = 0;
  for (point2D_t idx = 0; idx < num_points2D; ++idx) {
    const track_t track_id = tracks[idx];
    if (track_id != kInvalidTrackId) {
      num_added += ContinueOrTriangulateTrack(options, track_id, model);
    } else if (model->IsFree({image_id, idx}) &&
               ContinueKeypoint(options, {image_id, idx}, {}, model) != kInvalidPoint3DId) {
      ++num_added;
    }
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
