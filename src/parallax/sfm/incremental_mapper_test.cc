#include "parallax/sfm/incremental_mapper.h"

#include <gtest/gtest.h>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/similarity.h"
#include "parallax/scene/synthetic_dataset.h"

namespace parallax {
namespace {

// The mapper's input for a synthetic truth: its keypoints, and every pair sharing points
// verified with its true matches and essential matrix.
MapperInput InputFromTruth(const Reconstruction& truth) {
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
          matches[ImagePairToPairId(a.image_id, b.image_id)].push_back({a.point2D_idx, b.point2D_idx});
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

struct PoseErrors {
  double max_rotation_deg = 0;
  double max_center_error = 0;  // In truth units.
};

PoseErrors CompareToTruth(const Reconstruction& model, const Reconstruction& truth) {
  std::vector<Eigen::Vector3d> model_centers, truth_centers;
  for (const image_t image_id : model.RegImageIds()) {
    model_centers.push_back(model.GetImage(image_id).ProjectionCenter());
    truth_centers.push_back(truth.GetImage(image_id).ProjectionCenter());
  }
  const auto truth_from_model = EstimateSim3d(model_centers, truth_centers);
  EXPECT_TRUE(truth_from_model.has_value());
  PoseErrors errors;
  if (!truth_from_model) return errors;
  for (const image_t image_id : model.RegImageIds()) {
    const Rigid3d aligned = TransformCameraPose(*truth_from_model, model.GetImage(image_id).cam_from_world);
    const Rigid3d& expected = truth.GetImage(image_id).cam_from_world;
    errors.max_rotation_deg =
        std::max(errors.max_rotation_deg, RotationAngleDegrees(aligned.rotation, expected.rotation));
    errors.max_center_error = std::max(
        errors.max_center_error, (ProjectionCenter(aligned) - ProjectionCenter(expected)).norm());
  }
  return errors;
}

TEST(IncrementalMapper, NoiselessRingIsRecoveredToNumericalPrecision) {
  SyntheticDatasetOptions options;
  options.num_images = 16;
  options.num_points3D = 400;
  options.min_track_length = 3;
  options.seed = 3;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  const MapperInput input = InputFromTruth(truth);

  MapperSummary summary;
  IncrementalMapper mapper(IncrementalMapperOptions(), input);
  const std::vector<Reconstruction> models = mapper.Reconstruct(&summary);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth.NumRegImages());
  EXPECT_GE(models[0].NumPoints3D(), 0.95 * truth.NumPoints3D());
  Reconstruction copy = models[0];
  EXPECT_LT(copy.UpdatePointErrors(), 1e-6);
  const PoseErrors errors = CompareToTruth(models[0], truth);
  EXPECT_LT(errors.max_rotation_deg, 1e-6);
  EXPECT_LT(errors.max_center_error, 1e-6 * options.camera_distance);
  for (const auto& [image_id, report] : summary.images) {
    EXPECT_EQ(report.model_index, 0) << image_id;
    EXPECT_TRUE(report.reason.empty());
  }
}

TEST(IncrementalMapper, NoisyHemisphereWithDistortion) {
  SyntheticDatasetOptions options;
  options.num_images = 20;
  options.num_points3D = 600;
  options.layout = SyntheticDatasetOptions::Layout::kHemisphere;
  options.camera_model_id = CameraModelId::kSimpleRadial;
  options.distortion = -0.05;
  options.point2D_noise_stddev = 0.5;
  options.min_track_length = 3;
  options.seed = 11;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  const MapperInput input = InputFromTruth(truth);
  MapperSummary summary;
  IncrementalMapper mapper(IncrementalMapperOptions(), input);
  const std::vector<Reconstruction> models = mapper.Reconstruct(&summary);
  ASSERT_GE(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth.NumRegImages());
  Reconstruction copy = models[0];
  EXPECT_LT(copy.UpdatePointErrors(), 0.8);
  const PoseErrors errors = CompareToTruth(models[0], truth);
  EXPECT_LT(errors.max_rotation_deg, 0.1);
}

TEST(IncrementalMapper, UnrelatedImagesGiveNoModelAndReasons) {
  SyntheticDatasetOptions options;
  options.num_images = 4;
  options.num_points3D = 100;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  MapperInput input = InputFromTruth(truth);
  // Drop every verified pair: the images are unrelated.
  input = MapperInput();
  for (const auto& [camera_id, camera] : truth.Cameras()) input.cameras.emplace(camera_id, camera);
  for (const auto& [image_id, image] : truth.Images()) {
    Image copy = image;
    copy.registered = false;
    for (Point2D& point : copy.points2D) point.point3D_id = kInvalidPoint3DId;
    input.images.emplace(image_id, copy);
  }
  FinalizeMapperInput(MapperInputOptions(), &input);
  MapperSummary summary;
  IncrementalMapper mapper(IncrementalMapperOptions(), input);
  EXPECT_TRUE(mapper.Reconstruct(&summary).empty());
  EXPECT_FALSE(summary.failure.empty());
  for (const auto& [image_id, report] : summary.images) {
    EXPECT_EQ(report.model_index, -1);
    EXPECT_NE(report.reason.find("no verified matches"), std::string::npos) << report.reason;
  }
}

}  // namespace
}  // namespace parallax
