// The incremental mapper's steps one at a time, on exact synthetic rings: each step does
// what its comment says, and nothing else.
#include "parallax/sfm/model_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <sstream>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

struct Ring {
  explicit Ring(int num_images = 10, double noise_px = 0.0) {
    SyntheticDatasetOptions options;
    options.num_images = num_images;
    options.num_points3D = 400;
    options.min_track_length = 3;
    options.point2D_noise_stddev = noise_px;
    options.seed = 5;
    SynthesizeDataset(options, &truth);
    input = InputFromTruth(truth);
  }
  Reconstruction truth;
  MapperInput input;
};

class ModelBuilderTest : public ::testing::Test {
 protected:
  explicit ModelBuilderTest(int num_images = 10) : ring_(num_images) {}
  ModelBuilder MakeBuilder() {
    return ModelBuilder(options_, ring_.input, used_images_, &summary_, &progress_);
  }
  Ring ring_;
  IncrementalMapperOptions options_;
  std::set<image_t> used_images_;
  MapperSummary summary_;
  std::ostringstream progress_output_;
  ProgressReporter progress_{"test", 0, &progress_output_, /*is_terminal=*/false};
};

TEST_F(ModelBuilderTest, InitializeFromBestPairRegistersTwoImagesAndTriangulates) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  const Reconstruction& model = builder.Model();
  EXPECT_EQ(model.NumRegImages(), 2u);
  EXPECT_GE(static_cast<int>(model.NumPoints3D()), options_.init_min_num_inliers);
  Reconstruction copy = model;
  EXPECT_LT(copy.UpdatePointErrors(), 1e-6);
  const PoseErrors errors = CompareToTruth(model, ring_.truth);
  EXPECT_LT(errors.max_rotation_deg, 1e-6);
  for (const image_t image_id : model.RegImageIds()) {
    EXPECT_LT(summary_.images[image_id].error_before_ba_px, 1e-6);
  }
  EXPECT_EQ(summary_.num_global_ba, 1u);  // The initial pair is adjusted once.
}

TEST_F(ModelBuilderTest, InitializeFromPairRefusesAnAngleAboveThePairs) {
  ModelBuilder builder = MakeBuilder();
  const auto& [pair_id, geometry] = *ring_.input.two_view_geometries.begin();
  EXPECT_FALSE(
      builder.InitializeFromPair(pair_id, geometry, {options_.init_min_num_inliers, 89.0}));
  EXPECT_EQ(builder.Model().NumRegImages(), 0u);
  EXPECT_EQ(builder.Model().NumPoints3D(), 0u);
  EXPECT_TRUE(builder.InitializeFromPair(pair_id, geometry, {options_.init_min_num_inliers, 0.0}));
  EXPECT_EQ(builder.Model().NumRegImages(), 2u);
}

TEST_F(ModelBuilderTest, InitializationSkipsImagesOfEarlierModels) {
  for (image_t image_id = 1; image_id <= 9; ++image_id) used_images_.insert(image_id);
  ModelBuilder builder = MakeBuilder();
  EXPECT_FALSE(builder.InitializeFromBestPair());  // One image is left: no pair.
  EXPECT_EQ(builder.Model().NumRegImages(), 0u);
}

TEST_F(ModelBuilderTest, NextImagesAreUnregisteredAndSkipThoseOutOfTrials) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  const std::vector<image_t> next = builder.NextImages({});
  ASSERT_FALSE(next.empty());
  for (const image_t image_id : next) {
    EXPECT_FALSE(builder.Model().IsImageRegistered(image_id)) << image_id;
  }
  std::map<image_t, int> trials = {{next[0], options_.max_registration_trials}};
  const std::vector<image_t> without_first = builder.NextImages(trials);
  EXPECT_EQ(std::count(without_first.begin(), without_first.end(), next[0]), 0);
  EXPECT_EQ(without_first.size(), next.size() - 1);
}

TEST_F(ModelBuilderTest, RegisterImageFindsTheTruePoseAndTriangulatesItsTracks) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  const size_t observations_before = builder.Model().NumObservations();
  const image_t image_id = builder.NextImages({})[0];
  MapperImageReport report;
  ASSERT_TRUE(builder.RegisterImage(image_id, &report)) << report.reason;
  EXPECT_TRUE(report.reason.empty());
  EXPECT_GE(static_cast<int>(report.num_pnp_inliers), options_.absolute_pose_min_num_inliers);
  EXPECT_EQ(builder.Model().NumRegImages(), 3u);
  // Its keypoints joined the points they see.
  EXPECT_GE(builder.Model().NumObservations(),
            observations_before + static_cast<size_t>(report.num_pnp_inliers));
  EXPECT_LT(CompareToTruth(builder.Model(), ring_.truth).max_rotation_deg, 1e-5);
  EXPECT_FALSE(builder.ImagesLeftToRegister() && builder.NextImages({}).empty());
}

TEST_F(ModelBuilderTest, RegisterImageSaysWhyWhenTooFewPointsAreSeen) {
  options_.absolute_pose_min_num_inliers = 100000;
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  const image_t image_id = builder.NextImages({})[0];
  MapperImageReport report;
  EXPECT_FALSE(builder.RegisterImage(image_id, &report));
  EXPECT_NE(report.reason.find("too few 2D-3D correspondences"), std::string::npos);
  EXPECT_FALSE(builder.Model().IsImageRegistered(image_id));
}

TEST_F(ModelBuilderTest, FilterObservationsRemovesAPointMovedOffItsRays) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  EXPECT_EQ(builder.FilterObservations(), 0u);  // Exact points all fit.
  const point3D_t moved = builder.Model().Points3D().begin()->first;
  Point3D& point = builder.Model().GetPoint3D(moved);
  const size_t track_length = point.track.elements.size();
  point.xyz += Eigen::Vector3d(0.5, -0.5, 0.5);
  EXPECT_EQ(builder.FilterObservations(), track_length);
  EXPECT_FALSE(builder.Model().ExistsPoint3D(moved));
}

TEST_F(ModelBuilderTest, GlobalAdjustmentPullsAPerturbedImageBack) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  for (int i = 0; i < 3; ++i) {
    MapperImageReport report;
    ASSERT_TRUE(builder.RegisterImage(builder.NextImages({})[0], &report)) << report.reason;
  }
  const image_t last = builder.Model().RegImageIds().back();
  Rigid3d& pose = builder.Model().GetImage(last).cam_from_world;
  pose.translation += Eigen::Vector3d(1e-3, -1e-3, 1e-3);
  const size_t global_before = summary_.num_global_ba;
  builder.AdjustGlobalBundle();
  EXPECT_EQ(summary_.num_global_ba, global_before + 1);
  EXPECT_FALSE(builder.GrewSinceGlobalAdjustment());
  EXPECT_LT(CompareToTruth(builder.Model(), ring_.truth).max_rotation_deg, 1e-5);
  Reconstruction copy = builder.Model();
  EXPECT_LT(copy.UpdatePointErrors(), 1e-5);
}

TEST_F(ModelBuilderTest, LocalAdjustmentRunsAroundTheNewImageWithCamerasFixed) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  MapperImageReport report;
  const image_t image_id = builder.NextImages({})[0];
  ASSERT_TRUE(builder.RegisterImage(image_id, &report));
  const std::vector<double> params_before = builder.Model().Cameras().begin()->second.params;
  builder.AdjustLocalBundle(image_id);
  EXPECT_EQ(summary_.num_local_ba, 1u);
  EXPECT_EQ(builder.Model().Cameras().begin()->second.params, params_before);
  EXPECT_TRUE(builder.GrewSinceGlobalAdjustment());
}

TEST_F(ModelBuilderTest, InitializeFromModelKeepsTheSeedsPosesAndTriangulatesTheirTracks) {
  Reconstruction seed;
  for (const auto& [camera_id, camera] : ring_.truth.Cameras()) seed.AddCamera(camera);
  for (image_t image_id = 1; image_id <= 4; ++image_id) {
    Image image = ring_.truth.GetImage(image_id);
    for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
    seed.AddImage(image);
    seed.RegisterImage(image_id);
  }
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromModel(seed));
  EXPECT_EQ(builder.Model().NumRegImages(), 4u);
  EXPECT_GT(builder.Model().NumPoints3D(), 0u);
  for (image_t image_id = 1; image_id <= 4; ++image_id) {
    const Rigid3d& pose = builder.Model().GetImage(image_id).cam_from_world;
    EXPECT_TRUE(
        pose.translation.isApprox(ring_.truth.GetImage(image_id).cam_from_world.translation));
  }
  Reconstruction copy = builder.Model();
  EXPECT_LT(copy.UpdatePointErrors(), 1e-6);
}

TEST_F(ModelBuilderTest, CompleteTracksAddsObservationsThatFit) {
  ModelBuilder builder = MakeBuilder();
  ASSERT_TRUE(builder.InitializeFromBestPair());
  MapperImageReport report;
  ASSERT_TRUE(builder.RegisterImage(builder.NextImages({})[0], &report));
  // Registration triangulated the new image's tracks; remove one of its observations and
  // completion puts it back.
  const image_t image_id = builder.Model().RegImageIds().back();
  point2D_t removed_idx = 0;
  const Image& image = builder.Model().GetImage(image_id);
  while (!image.points2D[removed_idx].HasPoint3D()) ++removed_idx;
  builder.Model().DeleteObservation(image_id, removed_idx);
  ASSERT_FALSE(builder.Model().GetImage(image_id).points2D[removed_idx].HasPoint3D());
  EXPECT_GE(builder.CompleteTracks(), 1u);
  EXPECT_TRUE(builder.Model().GetImage(image_id).points2D[removed_idx].HasPoint3D());
}

}  // namespace
}  // namespace parallax
