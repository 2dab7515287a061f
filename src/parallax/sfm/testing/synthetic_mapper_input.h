#pragma once

// Test helpers shared by the mapper tests: a mapper input made from a synthetic truth, and
// pose errors against it after similarity alignment.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <vector>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/similarity.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/mapper_input.h"

namespace parallax {

// The mapper's input for a synthetic truth: its keypoints, and every pair sharing points
// verified with its true matches and essential matrix.
inline MapperInput InputFromTruth(const Reconstruction& truth) {
  MapperInput input;
  for (const auto& [camera_id, camera] : truth.Cameras()) {
    Camera known = camera;
    known.has_prior_focal_length = true;
    input.cameras.emplace(camera_id, known);
  }
  for (const auto& [image_id, image] : truth.Images()) {
    Image copy = image;
    copy.registered = false;
    copy.cam_from_world = Rigid3d();
    for (Point2D& point : copy.points2D) point.point3D_id = kInvalidPoint3DId;
    input.images.emplace(image_id, copy);
  }
  std::map<image_pair_t, FeatureMatches> matches;
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    for (const TrackElement& a : point.track.elements) {
      for (const TrackElement& b : point.track.elements) {
        if (a.image_id < b.image_id) {
          matches[ImagePairToPairId(a.image_id, b.image_id)].push_back(
              {a.point2D_idx, b.point2D_idx});
        }
      }
    }
  }
  for (auto& [pair_id, pair_matches] : matches) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    TwoViewGeometry geometry;
    geometry.config = TwoViewGeometry::kCalibrated;
    const Rigid3d cam2_from_cam1 = truth.GetImage(image_id2).cam_from_world *
                                   truth.GetImage(image_id1).cam_from_world.Inverse();
    geometry.E = EssentialFromPose(cam2_from_cam1);
    geometry.inlier_matches = pair_matches;
    input.two_view_geometries.emplace(pair_id, geometry);
  }
  FinalizeMapperInput(MapperInputOptions(), &input);
  return input;
}

// A ring of exact views, the mapper's input for it, and `model`: every image with its true
// pose, none registered and no points yet (for the triangulator's tests).
struct PosedSyntheticScene {
  explicit PosedSyntheticScene(int num_images = 8, int num_points3D = 300,
                               int min_track_length = 3) {
    SyntheticDatasetOptions options;
    options.num_images = num_images;
    options.num_points3D = num_points3D;
    options.min_track_length = min_track_length;
    options.seed = 21;
    SynthesizeDataset(options, &truth);
    input = InputFromTruth(truth);
    for (const auto& [camera_id, camera] : truth.Cameras()) model.AddCamera(camera);
    for (const auto& [image_id, image] : input.images) {
      Image posed = image;
      posed.cam_from_world = truth.GetImage(image_id).cam_from_world;
      model.AddImage(posed);
    }
  }

  void Register(image_t first, image_t last) {
    for (image_t image_id = first; image_id <= last; ++image_id) model.RegisterImage(image_id);
  }

  // The true point seen in a keypoint.
  point3D_t TruePointOf(const TrackElement& element) const {
    return truth.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id;
  }

  Reconstruction truth;
  MapperInput input;
  Reconstruction model;
};

struct PoseErrors {
  double max_rotation_deg = 0;
  double max_center_error = 0;  // In truth units.
};

// Aligns by the camera centres and a point ahead of each camera (one unit of the truth ahead,
// scaled to the model by the ratio of the centres' spreads), so that cameras in a line (the
// sequence layout) fix the rotation about that line too.
inline PoseErrors CompareToTruth(const Reconstruction& model, const Reconstruction& truth) {
  std::vector<Eigen::Vector3d> model_centers, truth_centers;
  for (const image_t image_id : model.RegImageIds()) {
    model_centers.push_back(model.GetImage(image_id).ProjectionCenter());
    truth_centers.push_back(truth.GetImage(image_id).ProjectionCenter());
  }
  const auto spread = [](const std::vector<Eigen::Vector3d>& points) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& point : points) mean += point / points.size();
    double sum = 0;
    for (const Eigen::Vector3d& point : points) sum += (point - mean).norm();
    return sum;
  };
  const double model_per_truth = spread(model_centers) / spread(truth_centers);
  const std::vector<image_t> image_ids = model.RegImageIds();
  for (size_t i = 0; i < image_ids.size(); ++i) {
    model_centers.push_back(model_centers[i] +
                            model_per_truth * model.GetImage(image_ids[i]).ViewingDirection());
    truth_centers.push_back(truth_centers[i] + truth.GetImage(image_ids[i]).ViewingDirection());
  }
  const auto truth_from_model = EstimateSim3d(model_centers, truth_centers);
  EXPECT_TRUE(truth_from_model.has_value());
  PoseErrors errors;
  if (!truth_from_model) return errors;
  for (const image_t image_id : model.RegImageIds()) {
    const Rigid3d aligned =
        TransformCameraPose(*truth_from_model, model.GetImage(image_id).cam_from_world);
    const Rigid3d& expected = truth.GetImage(image_id).cam_from_world;
    errors.max_rotation_deg = std::max(errors.max_rotation_deg,
                                       RotationAngleDegrees(aligned.rotation, expected.rotation));
    errors.max_center_error = std::max(
        errors.max_center_error, (ProjectionCenter(aligned) - ProjectionCenter(expected)).norm());
  }
  return errors;
}

}  // namespace parallax
