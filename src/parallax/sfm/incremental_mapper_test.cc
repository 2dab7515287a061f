#include "parallax/sfm/incremental_mapper.h"

#include <gtest/gtest.h>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

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

TEST(IncrementalMapper, ExtendsASeedOfKnownPosesToTheWholeScene) {
  SyntheticDatasetOptions options;
  options.num_images = 16;
  options.num_points3D = 400;
  options.min_track_length = 3;
  options.point2D_noise_stddev = 0.3;
  options.seed = 5;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  const MapperInput input = InputFromTruth(truth);
  // The seed: the first six images with their true poses in a frame of its own (scaled,
  // turned and moved), and no points.
  const Sim3d seed_from_truth(
      2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(4, -1, 2));
  Reconstruction seed;
  for (const auto& [camera_id, camera] : truth.Cameras()) seed.AddCamera(camera);
  for (image_t image_id = 1; image_id <= 6; ++image_id) {
    Image image = truth.GetImage(image_id);
    image.cam_from_world = TransformCameraPose(seed_from_truth, image.cam_from_world);
    for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
    image.registered = false;
    seed.AddImage(image);
    seed.RegisterImage(image_id);
  }

  MapperSummary summary;
  IncrementalMapper mapper(IncrementalMapperOptions(), input);
  const std::vector<Reconstruction> models = mapper.Extend(seed, &summary);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth.NumRegImages());
  EXPECT_GE(models[0].NumPoints3D(), 0.9 * truth.NumPoints3D());
  // The seed's frame is kept: its images stay close to where the seed put them.
  for (image_t image_id = 1; image_id <= 6; ++image_id) {
    EXPECT_LT((models[0].GetImage(image_id).ProjectionCenter() -
               seed.GetImage(image_id).ProjectionCenter())
                  .norm(),
              1e-2 * seed_from_truth.scale * options.camera_distance)
        << image_id;
  }
  const PoseErrors errors = CompareToTruth(models[0], truth);
  EXPECT_LT(errors.max_rotation_deg, 0.05);
  EXPECT_LT(errors.max_center_error, 1e-3 * options.camera_distance);
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
