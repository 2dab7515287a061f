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

  // Every phase ran, the phases fit in the run, and the solver took part of it.
  EXPECT_GT(summary.num_local_ba, 0u);
  for (const auto& [name, seconds] : summary.phase_seconds.Named()) {
    EXPECT_GT(seconds, 0.0) << name;
  }
  EXPECT_LE(summary.phase_seconds.Total(), summary.seconds);
  EXPECT_GT(summary.BaSeconds(), 0.0);
  EXPECT_LT(summary.BaSeconds(), summary.phase_seconds.Total());
}

// The first `num_seed_images` images of `truth` with their true poses in a frame of their
// own (`seed_from_truth`: scaled, turned and moved), and no points.
Reconstruction SeedOfFirstImages(const Reconstruction& truth, image_t num_seed_images,
                                 const Sim3d& seed_from_truth) {
  Reconstruction seed;
  for (const auto& [camera_id, camera] : truth.Cameras()) seed.AddCamera(camera);
  for (image_t image_id = 1; image_id <= num_seed_images; ++image_id) {
    Image image = truth.GetImage(image_id);
    image.cam_from_world = TransformCameraPose(seed_from_truth, image.cam_from_world);
    for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
    image.registered = false;
    seed.AddImage(image);
    seed.RegisterImage(image_id);
  }
  return seed;
}

SyntheticDatasetOptions NoisyRingOptions() {
  SyntheticDatasetOptions options;
  options.num_images = 16;
  options.num_points3D = 400;
  options.min_track_length = 3;
  options.point2D_noise_stddev = 0.3;
  options.seed = 5;
  return options;
}

const Sim3d kSeedFromTruth(
    2.5, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
    Eigen::Vector3d(4, -1, 2));

// The noisy ring mapped by extending a seed of its first images.
class ExtendTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SynthesizeDataset(options_, &truth_);
    input_ = InputFromTruth(truth_);
  }
  std::vector<Reconstruction> Extend(image_t num_seed_images) {
    seed_ = SeedOfFirstImages(truth_, num_seed_images, kSeedFromTruth);
    IncrementalMapper mapper(IncrementalMapperOptions(), input_);
    return mapper.Extend(seed_, &summary_);
  }
  const SyntheticDatasetOptions options_ = NoisyRingOptions();
  Reconstruction truth_;
  MapperInput input_;
  Reconstruction seed_;
  MapperSummary summary_;
};

TEST_F(ExtendTest, SeedOfKnownPosesGrowsToTheWholeScene) {
  const std::vector<Reconstruction> models = Extend(6);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth_.NumRegImages());
  EXPECT_GE(models[0].NumPoints3D(), 0.9 * truth_.NumPoints3D());
  // The seed's frame is kept: its images stay close to where the seed put them.
  for (image_t image_id = 1; image_id <= 6; ++image_id) {
    EXPECT_LT((models[0].GetImage(image_id).ProjectionCenter() -
               seed_.GetImage(image_id).ProjectionCenter())
                  .norm(),
              1e-2 * kSeedFromTruth.scale * options_.camera_distance)
        << image_id;
  }
  const PoseErrors errors = CompareToTruth(models[0], truth_);
  EXPECT_LT(errors.max_rotation_deg, 0.05);
  EXPECT_LT(errors.max_center_error, 1e-3 * options_.camera_distance);
  // Ten new images outnumber the seed's six: global adjustments as the model grows, and the
  // final one's refinement rounds, as in a run from scratch.
  EXPECT_GE(summary_.num_global_ba, 2u);
}

// A few photos added to a finished model: each is settled by a local adjustment, then one
// global round, and the model is as accurate as one mapped from scratch.
TEST_F(ExtendTest, FewImagesAddedGetLocalThenOneGlobalAdjustment) {
  const std::vector<Reconstruction> models = Extend(12);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth_.NumRegImages());
  EXPECT_EQ(summary_.num_local_ba, 4u);
  EXPECT_EQ(summary_.num_global_ba, 1u);

  MapperSummary scratch_summary;
  IncrementalMapper scratch_mapper(IncrementalMapperOptions(), input_);
  const std::vector<Reconstruction> scratch = scratch_mapper.Reconstruct(&scratch_summary);
  ASSERT_EQ(scratch.size(), 1u);
  const PoseErrors errors = CompareToTruth(models[0], truth_);
  const PoseErrors scratch_errors = CompareToTruth(scratch[0], truth_);
  EXPECT_LT(errors.max_rotation_deg, std::max(0.05, 1.1 * scratch_errors.max_rotation_deg));
  EXPECT_LT(errors.max_center_error,
            std::max(1e-3 * options_.camera_distance, 1.1 * scratch_errors.max_center_error));
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

// An image that sees only 20 of the model's points misses the 30 PnP inliers registration
// asks for; the last pass, at the relaxed 15, registers it and says so in its report.
TEST(IncrementalMapper, TheLastPassRegistersAnImageBelowTheBarsAtRelaxedOnes) {
  SyntheticDatasetOptions options;
  options.num_images = 12;
  options.num_points3D = 400;
  options.min_track_length = 3;
  options.seed = 4;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  const image_t sparse_image = 12;
  std::vector<point2D_t> observed;
  const Image& image = truth.GetImage(sparse_image);
  for (point2D_t idx = 0; idx < image.points2D.size(); ++idx) {
    if (image.points2D[idx].HasPoint3D()) observed.push_back(idx);
  }
  ASSERT_GT(observed.size(), 40u);
  for (size_t i = 20; i < observed.size(); ++i) truth.DeleteObservation(sparse_image, observed[i]);
  const MapperInput input = InputFromTruth(truth);

  MapperSummary summary;
  const std::vector<Reconstruction> models =
      IncrementalMapper(IncrementalMapperOptions(), input).Reconstruct(&summary);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth.NumRegImages());
  const MapperImageReport& report = summary.images[sparse_image];
  EXPECT_TRUE(report.registered_relaxed);
  EXPECT_GE(report.num_relaxed_registration_trials, 1);
  EXPECT_GT(report.num_registration_trials, report.num_relaxed_registration_trials);
  for (const auto& [image_id, other] : summary.images) {
    if (image_id != sparse_image) EXPECT_FALSE(other.registered_relaxed) << image_id;
  }
  EXPECT_LT(CompareToTruth(models[0], truth).max_rotation_deg, 1e-6);

  // Relaxed bars no lower than the usual ones: the image stays out, its retries counted.
  IncrementalMapperOptions strict;
  strict.relaxed_absolute_pose_min_num_inliers = strict.absolute_pose_min_num_inliers;
  const std::vector<Reconstruction> without =
      IncrementalMapper(strict, input).Reconstruct(&summary);
  ASSERT_EQ(without.size(), 1u);
  EXPECT_EQ(without[0].NumRegImages(), truth.NumRegImages() - 1);
  EXPECT_EQ(summary.images[sparse_image].model_index, -1);
  EXPECT_GE(summary.images[sparse_image].num_relaxed_registration_trials, 1);
  EXPECT_NE(summary.images[sparse_image].reason.find("relaxed"), std::string::npos)
      << summary.images[sparse_image].reason;
}

}  // namespace
}  // namespace parallax
