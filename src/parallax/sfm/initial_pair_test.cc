// The initialiser's relaxation: the order of the thresholds, and that a model starts at the
// first step some pair meets, on exact synthetic views whose angles are known.
#include "parallax/sfm/initial_pair.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "parallax/geometry/triangulation.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/incremental_mapper.h"
#include "parallax/sfm/model_builder.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

std::vector<std::pair<int, double>> Steps(const IncrementalMapperOptions& options) {
  std::vector<std::pair<int, double>> steps;
  for (const InitThresholds& thresholds : InitThresholdSchedule(options)) {
    EXPECT_EQ(thresholds.step, static_cast<int>(steps.size()));
    steps.emplace_back(thresholds.min_num_inliers, thresholds.min_angle_deg);
  }
  return steps;
}

TEST(InitThresholdSchedule, HalvesTheAngleThenTheInliersInTurnsDownToTheFloors) {
  IncrementalMapperOptions options;  // 100 inliers at 16 degrees, floors 25 and 2.
  const std::vector<std::pair<int, double>> expected = {{100, 16.0}, {100, 8.0}, {50, 8.0},
                                                        {50, 4.0},   {25, 4.0},  {25, 2.0}};
  EXPECT_EQ(Steps(options), expected);
}

TEST(InitThresholdSchedule, OneAtItsFloorLeavesTheOtherToHalve) {
  IncrementalMapperOptions options;
  options.init_min_num_inliers = 30;  // Floor 25: one halving reaches it.
  options.init_min_triangulation_angle_deg = 16.0;
  const std::vector<std::pair<int, double>> expected = {
      {30, 16.0}, {30, 8.0}, {25, 8.0}, {25, 4.0}, {25, 2.0}};
  EXPECT_EQ(Steps(options), expected);
}

TEST(InitThresholdSchedule, ThresholdsBelowTheFloorsAreNotRelaxed) {
  IncrementalMapperOptions options;
  options.init_min_num_inliers = 20;
  options.init_min_triangulation_angle_deg = 1.0;
  const std::vector<std::pair<int, double>> expected = {{20, 1.0}};
  EXPECT_EQ(Steps(options), expected);
  options.init_min_num_inliers_floor = options.init_min_num_inliers;
  options.init_min_triangulation_angle_floor_deg = options.init_min_triangulation_angle_deg;
  EXPECT_EQ(Steps(options), expected);
}

// A walk along a slab of points: consecutive views a few degrees apart, so that the given
// 16 degrees are met by no pair and the model starts after relaxation.
struct Walk {
  Walk() {
    SyntheticDatasetOptions options;
    options.layout = SyntheticDatasetOptions::Layout::kSequence;
    options.num_images = 8;
    options.num_points3D = 500;
    options.min_track_length = 3;
    options.sequence_step = 0.25;
    options.camera_distance = 6.0;
    options.seed = 3;
    SynthesizeDataset(options, &truth);
    input = InputFromTruth(truth);
  }
  // The input's cameras and images, none registered: what EvaluateInitialPair reads.
  Reconstruction Unregistered() const {
    Reconstruction unregistered;
    for (const auto& [camera_id, camera] : input.cameras) unregistered.AddCamera(camera);
    for (const auto& [image_id, image] : input.images) unregistered.AddImage(image);
    return unregistered;
  }
  Reconstruction truth;
  MapperInput input;
};

TEST(InitialPair, EvaluationMeasuresTheTrueAngleOfExactMatches) {
  const Walk walk;
  const Reconstruction unregistered = walk.Unregistered();
  for (const auto& [pair_id, geometry] : walk.input.two_view_geometries) {
    const InitialPairEvaluation evaluation =
        EvaluateInitialPair(unregistered, pair_id, geometry, /*max_error_px=*/1.0);
    ASSERT_TRUE(evaluation.has_pose);
    // Exact matches under the exact pose: every one triangulates.
    EXPECT_EQ(evaluation.num_triangulated, static_cast<int>(geometry.inlier_matches.size()));
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    std::vector<double> angles;
    for (const FeatureMatch& match : geometry.inlier_matches) {
      const point3D_t point3D_id =
          walk.truth.GetImage(image_id1).points2D[match.point2D_idx1].point3D_id;
      angles.push_back(
          CalculateTriangulationAngle(walk.truth.GetImage(image_id1).ProjectionCenter(),
                                      walk.truth.GetImage(image_id2).ProjectionCenter(),
                                      walk.truth.GetPoint3D(point3D_id).xyz) *
          180.0 / M_PI);
    }
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    EXPECT_NEAR(evaluation.median_angle_deg, angles[angles.size() / 2], 1e-6);
  }
}

TEST(InitialPair, TheModelStartsAtTheFirstStepSomePairMeets) {
  const Walk walk;
  IncrementalMapperOptions options;
  options.init_min_num_inliers = 60;
  // One adjusted pair per step: every candidate is still held to each step's thresholds
  // (the pair that meets them need not be among those with most inliers).
  options.init_max_trials = 1;
  // Which step the schedule should stop at, from each pair's evaluation.
  const Reconstruction unregistered = walk.Unregistered();
  int expected_step = -1;
  for (const InitThresholds& thresholds : InitThresholdSchedule(options)) {
    for (const auto& [pair_id, geometry] : walk.input.two_view_geometries) {
      const InitialPairEvaluation evaluation = EvaluateInitialPair(
          unregistered, pair_id, geometry, options.triangulation.max_reprojection_error_px);
      if (evaluation.num_triangulated >= thresholds.min_num_inliers &&
          evaluation.median_angle_deg >= thresholds.min_angle_deg) {
        expected_step = thresholds.step;
        break;
      }
    }
    if (expected_step >= 0) break;
  }
  ASSERT_GT(expected_step, 0) << "the walk should need relaxing";

  MapperSummary summary;
  IncrementalMapper mapper(options, walk.input);
  const std::vector<Reconstruction> models = mapper.Reconstruct(&summary);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), walk.input.images.size());
  ASSERT_EQ(summary.models.size(), 1u);
  const ModelStartReport& start = summary.models[0].start;
  EXPECT_FALSE(start.from_input_model);
  EXPECT_EQ(start.thresholds.step, expected_step);
  EXPECT_GE(start.median_angle_deg, start.thresholds.min_angle_deg);
  EXPECT_GE(start.num_triangulated, start.thresholds.min_num_inliers);
  EXPECT_LT(CompareToTruth(models[0], walk.truth).max_rotation_deg, 1e-3);

  // With the floors at the given thresholds nothing starts, and the failure says so.
  options.init_min_num_inliers_floor = options.init_min_num_inliers;
  options.init_min_triangulation_angle_floor_deg = options.init_min_triangulation_angle_deg;
  IncrementalMapper strict(options, walk.input);
  EXPECT_TRUE(strict.Reconstruct(&summary).empty());
  EXPECT_NE(summary.failure.find("even relaxed to 60 and 16 deg"), std::string::npos)
      << summary.failure;
}

// Three images that share more matches than any other pair but nothing with the rest: the
// model they start is smaller than min_model_size and discarded, and the next start, from
// another pair, maps the rest.
TEST(InitialPair, AStartThatEndsTooSmallIsDiscardedAndAnotherPairTried) {
  const Walk walk;
  MapperInput input = walk.input;
  SyntheticDatasetOptions island_options;
  island_options.num_images = 3;
  island_options.min_track_length = 3;
  island_options.num_points3D = 900;
  island_options.seed = 8;
  Reconstruction island;
  SynthesizeDataset(island_options, &island);
  const MapperInput island_input = InputFromTruth(island);
  const image_t offset = 100;
  for (const auto& [image_id, image] : island_input.images) {
    Image copy = image;
    copy.image_id = image_id + offset;
    copy.name = "island_" + image.name;
    input.images.emplace(copy.image_id, copy);
  }
  for (const auto& [pair_id, geometry] : island_input.two_view_geometries) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    input.two_view_geometries.emplace(ImagePairToPairId(image_id1 + offset, image_id2 + offset),
                                      geometry);
  }
  size_t most_walk_matches = 0;
  for (const auto& [pair_id, geometry] : walk.input.two_view_geometries) {
    most_walk_matches = std::max(most_walk_matches, geometry.inlier_matches.size());
  }
  ASSERT_EQ(island_input.two_view_geometries.size(), 3u);
  ASSERT_GT(island_input.two_view_geometries.begin()->second.inlier_matches.size(),
            most_walk_matches);
  input.correspondence_graph = CorrespondenceGraph();  // Built anew with the island.
  FinalizeMapperInput(MapperInputOptions(), &input);

  IncrementalMapperOptions options;
  options.init_min_triangulation_angle_deg = 2.0;  // The walk starts without relaxing.
  options.min_model_size = 4;
  MapperSummary summary;
  const std::vector<Reconstruction> models =
      IncrementalMapper(options, input).Reconstruct(&summary);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), walk.input.images.size());
  EXPECT_EQ(summary.num_discarded_models, 1);
  for (const image_t image_id : {offset + 1, offset + 2, offset + 3}) {
    EXPECT_EQ(summary.images[image_id].model_index, -1);
    EXPECT_NE(summary.images[image_id].reason.find("discarded"), std::string::npos)
        << summary.images[image_id].reason;
  }
}

}  // namespace
}  // namespace parallax
