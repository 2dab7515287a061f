#include "parallax/pipeline/matching_stage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "parallax/math/random.h"
#include "parallax/pipeline/pair_batch_matcher.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// A database with exact ground truth: `num_images` cameras on an arc looking at a cloud of
// points; every image observes every point (in a shuffled keypoint order) with the point's
// descriptor, plus `num_clutter` keypoints with random descriptors.
class FeatureMatchingTest : public ::testing::Test {
 protected:
  void MakeScene(Database* database, int num_images, int num_points, int num_clutter) {
    std::vector<Eigen::Vector3d> points(num_points);
    FeatureDescriptors point_descriptors(num_points, 128);
    for (int j = 0; j < num_points; ++j) {
      points[j] = Eigen::Vector3d(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                                  RandomUniformReal(-1, 1));
      for (int d = 0; d < 128; ++d) {
        point_descriptors(j, d) = static_cast<uint8_t>(RandomUniformInteger(0, 255));
      }
    }
    const Camera camera = Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 800, 640, 480);
    const camera_t camera_id = database->WriteCamera(camera);
    point_of_keypoint_.assign(num_images + 1, {});
    for (int i = 0; i < num_images; ++i) {
      // Camera centres on an arc at distance 6, looking at the origin.
      const double angle = 0.15 * i;
      const Eigen::Vector3d center(6 * std::sin(angle), 0.2 * i, -6 * std::cos(angle));
      const Eigen::Vector3d z = -center.normalized();
      const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
      Eigen::Matrix3d rotation;
      rotation << x.transpose(), z.cross(x).transpose(), z.transpose();
      const Rigid3d cam_from_world(rotation, -rotation * center);

      std::vector<int> order(num_points + num_clutter);
      for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
      Shuffle(order.size(), &order);
      FeatureKeypoints keypoints;
      FeatureDescriptors descriptors(order.size(), 128);
      std::vector<int> point_of_keypoint;
      for (size_t k = 0; k < order.size(); ++k) {
        const int j = order[k];
        if (j < num_points) {
          const Eigen::Vector2d xy = camera.ImgFromCam(cam_from_world * points[j]);
          keypoints.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()));
          descriptors.row(k) = point_descriptors.row(j);
          point_of_keypoint.push_back(j);
        } else {
          keypoints.emplace_back(RandomUniformReal(0, 640), RandomUniformReal(0, 480));
          for (int d = 0; d < 128; ++d) {
            descriptors(k, d) = static_cast<uint8_t>(RandomUniformInteger(0, 255));
          }
          point_of_keypoint.push_back(-1);
        }
      }
      // Names in reverse id order: pairs follow names, not ids.
      const image_t image_id = database->WriteImageWithFeatures(
          "view" + std::to_string(num_images - i) + ".png", camera_id, keypoints, descriptors);
      point_of_keypoint_[image_id] = point_of_keypoint;
    }
  }

  // True when the match links two observations of the same point.
  bool IsCorrect(image_t image_id1, image_t image_id2, const FeatureMatch& match) const {
    const int point1 = point_of_keypoint_.at(image_id1).at(match.point2D_idx1);
    return point1 >= 0 && point1 == point_of_keypoint_.at(image_id2).at(match.point2D_idx2);
  }

  const test::ScopedTestDir scoped_dir_{"parallax_feature_matching_test"};
  const fs::path dir_ = scoped_dir_.path();
  std::vector<std::vector<int>> point_of_keypoint_;
};

TEST(PairSelection, ExhaustiveBlocksCoverEveryPairOnce) {
  std::vector<image_t> ids;
  for (image_t id = 11; id <= 18; ++id) ids.push_back(id);
  for (int block_size : {1, 3, 8, 50}) {
    const auto pairs = ExhaustivePairs(ids, block_size);
    ASSERT_EQ(pairs.size(), 28u);
    std::set<std::pair<image_t, image_t>> unique(pairs.begin(), pairs.end());
    EXPECT_EQ(unique.size(), 28u);
    for (const auto& [a, b] : pairs) EXPECT_LT(a, b);  // Position order (ids sorted here).
  }
  EXPECT_TRUE(ExhaustivePairs({}, 50).empty());
  EXPECT_TRUE(ExhaustivePairs({5}, 50).empty());
}

TEST(PairSelection, SequentialOverlap) {
  const std::vector<image_t> ids = {4, 2, 9, 7, 1};
  const auto pairs = SequentialPairs(ids, 2);
  const std::vector<std::pair<image_t, image_t>> expected = {{4, 2}, {4, 9}, {2, 9}, {2, 7},
                                                             {9, 7}, {9, 1}, {7, 1}};
  EXPECT_EQ(pairs, expected);
  EXPECT_EQ(SequentialPairs(ids, 10).size(), 10u);
  EXPECT_EQ(PairModeFromName("sequential"), PairMode::kSequential);
  EXPECT_FALSE(PairModeFromName("vocab_tree").has_value());
}

// The batch matcher's steps one at a time: load, match and verify, store.
TEST_F(FeatureMatchingTest, BatchMatcherStepsLoadMatchVerifyAndStore) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 3, 120, 40);
  MatchingStageOptions options;
  options.num_threads = 1;
  std::unordered_map<camera_t, Camera> cameras;
  for (Camera& camera : database.ReadAllCameras()) cameras[camera.camera_id] = camera;
  std::unordered_map<image_t, camera_t> camera_of_image;
  for (const Image& image : database.ReadAllImages()) {
    camera_of_image[image.image_id] = image.camera_id;
  }
  PairBatchMatcher matcher(options, database, cameras, camera_of_image, /*cells=*/nullptr);
  matcher.LoadFeatures({1, 2});
  EXPECT_EQ(matcher.Features(1).points.size(), 160u);
  EXPECT_THROW(matcher.Features(3), std::out_of_range);  // Not loaded.

  PairJob job;
  job.image_id1 = 1;
  job.image_id2 = 2;
  matcher.MatchAndVerify(&job);
  EXPECT_TRUE(job.done);
  EXPECT_EQ(job.matches.size(), 120u);  // Identical descriptors: every point, nothing else.
  for (const FeatureMatch& match : job.matches) EXPECT_TRUE(IsCorrect(1, 2, match));
  // The scene's camera has no prior focal length: verified by F.
  EXPECT_EQ(job.geometry.config, TwoViewGeometry::kUncalibrated);
  EXPECT_GE(job.geometry.inlier_matches.size(), 115u);

  // Too few matches to verify: degenerate, so that a resumed run does not retry the pair.
  PairJob few = job;
  few.has_matches = true;
  few.matches.resize(options.geometry.min_num_inliers - 1);
  few.geometry = TwoViewGeometry();
  matcher.MatchAndVerify(&few);
  EXPECT_EQ(few.geometry.config, TwoViewGeometry::kDegenerate);

  PairJob unfinished;  // A pair a signal stopped before it ran is not stored.
  unfinished.image_id1 = 2;
  unfinished.image_id2 = 3;
  PairBatchMatcher::StoreJobs({job, unfinished}, &database);
  EXPECT_TRUE(database.ExistsTwoViewGeometry(1, 2));
  EXPECT_EQ(database.ReadMatches(1, 2).size(), 120u);
  EXPECT_FALSE(database.ExistsTwoViewGeometry(2, 3));
  EXPECT_FALSE(database.ExistsMatches(2, 3));
}

TEST_F(FeatureMatchingTest, ExhaustiveMatchesAndVerifiesEveryPair) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 4, 150, 60);
  MatchingStageOptions options;
  options.num_threads = 2;
  const MatchingStageResult stats = RunMatchingStage(options, &database);
  // auto: 210 descriptors per image, under the 512 from which cells are used.
  EXPECT_FALSE(stats.approximate);
  EXPECT_EQ(stats.num_pairs, 6u);
  EXPECT_EQ(stats.num_matched, 6u);
  EXPECT_EQ(stats.num_skipped, 0u);
  EXPECT_EQ(stats.num_verified, 6u);
  ASSERT_EQ(stats.pairs.size(), 6u);
  EXPECT_EQ(database.NumMatchedPairs(), 6u);
  EXPECT_EQ(database.NumVerifiedPairs(), 6u);
  for (const PairMatchStats& pair : stats.pairs) {
    // Identical descriptors: every point is matched and nothing else.
    EXPECT_EQ(pair.num_putative, 150);
    EXPECT_GE(pair.num_inliers, 145);
    const FeatureMatches matches = database.ReadMatches(pair.image_id1, pair.image_id2);
    EXPECT_EQ(matches.size(), 150u);
    for (const FeatureMatch& match : matches) {
      EXPECT_TRUE(IsCorrect(pair.image_id1, pair.image_id2, match));
    }
    const TwoViewGeometry geometry = database.ReadTwoViewGeometry(pair.image_id1, pair.image_id2);
    EXPECT_EQ(static_cast<int>(geometry.inlier_matches.size()), pair.num_inliers);
    EXPECT_EQ(geometry.config, pair.config);
    for (const FeatureMatch& match : geometry.inlier_matches) {
      EXPECT_TRUE(IsCorrect(pair.image_id1, pair.image_id2, match));
    }
  }

  // A second run finds everything done.
  const MatchingStageResult again = RunMatchingStage(options, &database);
  EXPECT_EQ(again.num_pairs, 6u);
  EXPECT_EQ(again.num_skipped, 6u);
  EXPECT_EQ(again.num_matched, 0u);
  EXPECT_EQ(database.NumVerifiedPairs(), 6u);
}

TEST_F(FeatureMatchingTest, SequentialPairsFollowNamesAndResume) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 5, 100, 20);
  // Pairs stored by an earlier, interrupted run: one fully verified, one with matches only.
  database.WriteTwoViewGeometry(5, 4, TwoViewGeometry());
  MatchingStageOptions options;
  options.pairs.mode = PairMode::kSequential;
  options.pairs.sequential_overlap = 1;
  options.batch_size = 2;
  options.num_threads = 2;
  {
    // Matches for (3, 2): the true correspondences of 40 points.
    FeatureMatches matches;
    for (point2D_t k = 0; k < point_of_keypoint_[3].size() && matches.size() < 40; ++k) {
      const int point = point_of_keypoint_[3][k];
      if (point < 0) continue;
      for (point2D_t l = 0; l < point_of_keypoint_[2].size(); ++l) {
        if (point_of_keypoint_[2][l] == point) matches.push_back({k, l});
      }
    }
    database.WriteMatches(3, 2, matches);
  }
  const MatchingStageResult stats = RunMatchingStage(options, &database);
  // Names view1..view5 belong to ids 5..1, so the sequence is 5-4, 4-3, 3-2, 2-1.
  EXPECT_EQ(stats.num_pairs, 4u);
  EXPECT_EQ(stats.num_skipped, 1u);
  EXPECT_EQ(stats.num_matched, 3u);
  EXPECT_EQ(stats.num_verified, 3u);
  std::set<std::pair<image_t, image_t>> processed;
  for (const PairMatchStats& pair : stats.pairs) {
    processed.insert({pair.image_id1, pair.image_id2});
    if (pair.image_id1 == 3 && pair.image_id2 == 2) {
      EXPECT_EQ(pair.num_putative, 40);  // Verified from the stored matches.
      EXPECT_GE(pair.num_inliers, 38);
    } else {
      EXPECT_EQ(pair.num_putative, 100);
    }
  }
  const std::set<std::pair<image_t, image_t>> expected = {{4, 3}, {3, 2}, {2, 1}};
  EXPECT_EQ(processed, expected);
  EXPECT_EQ(database.ReadMatches(2, 3).size(), 40u);
  EXPECT_FALSE(database.ExistsTwoViewGeometry(1, 3));
}

TEST_F(FeatureMatchingTest, PairsWithoutCommonPointsAreDegenerate) {
  Database database(dir_ / "database.db");
  const camera_t camera_id = database.WriteCamera(
      Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 800, 640, 480));
  for (const char* name : {"a.png", "b.png"}) {
    FeatureKeypoints keypoints;
    FeatureDescriptors descriptors(80, 128);
    for (int k = 0; k < 80; ++k) {
      keypoints.emplace_back(RandomUniformReal(0, 640), RandomUniformReal(0, 480));
      for (int d = 0; d < 128; ++d) {
        descriptors(k, d) = static_cast<uint8_t>(RandomUniformInteger(0, 255));
      }
    }
    database.WriteImageWithFeatures(name, camera_id, keypoints, descriptors);
  }
  const MatchingStageResult stats = RunMatchingStage(MatchingStageOptions(), &database);
  ASSERT_EQ(stats.pairs.size(), 1u);
  EXPECT_EQ(stats.num_verified, 0u);
  EXPECT_LT(stats.pairs[0].num_putative, 15);
  EXPECT_EQ(stats.pairs[0].num_inliers, 0);
  EXPECT_EQ(database.ReadTwoViewGeometry(1, 2).config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(database.ExistsTwoViewGeometry(1, 2));
}

TEST_F(FeatureMatchingTest, PreemptiveTestStopsUnrelatedPairsOnly) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 4, 150, 60);
  // Two images of clutter only: they share nothing with anything.
  const camera_t camera_id = database.ReadAllCameras().front().camera_id;
  for (const std::string name : {"clutter1.png", "clutter2.png"}) {
    FeatureKeypoints keypoints;
    FeatureDescriptors descriptors(200, 128);
    for (int k = 0; k < 200; ++k) {
      keypoints.emplace_back(static_cast<float>(RandomUniformReal(0, 640)),
                             static_cast<float>(RandomUniformReal(0, 480)));
      for (int d = 0; d < 128; ++d)
        descriptors(k, d) = static_cast<uint8_t>(RandomUniformInteger(0, 255));
    }
    database.WriteImageWithFeatures(name, camera_id, keypoints, descriptors);
  }
  MatchingStageOptions options;
  options.num_threads = 2;
  options.preemptive.enabled = true;
  options.preemptive.num_features = 50;
  const MatchingStageResult stats = RunMatchingStage(options, &database);
  EXPECT_TRUE(stats.preemptive);
  EXPECT_EQ(stats.num_pairs, 15u);
  // The 9 pairs with a clutter image are stopped; the 6 scene pairs all pass and verify.
  EXPECT_EQ(stats.num_preemptive_rejected, 9u);
  EXPECT_EQ(stats.num_verified, 6u);
  for (const PairMatchStats& pair : stats.pairs) {
    EXPECT_GE(pair.num_preemptive_matches, 0);
    EXPECT_EQ(pair.preemptive_rejected,
              pair.num_preemptive_matches < options.preemptive.min_matches);
    if (pair.preemptive_rejected) {
      EXPECT_EQ(pair.num_putative, 0);
      EXPECT_EQ(pair.config, TwoViewGeometry::kDegenerate);
    }
  }
  // Stopped pairs are stored: a rerun does not test them again.
  const MatchingStageResult again = RunMatchingStage(options, &database);
  EXPECT_EQ(again.num_skipped, 15u);
  EXPECT_EQ(again.num_matched, 0u);
}

// `auto` on exhaustive pairs: cells from 512 descriptors per image on average (COLMAP 4's
// rule), exact below.
TEST_F(FeatureMatchingTest, AutoMatchesInCellsFromFiveHundredTwelveDescriptorsPerImage) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 3, 500, 20);  // 520 descriptors per image.
  MatchingStageOptions options;
  options.num_threads = 2;
  const MatchingStageResult stats = RunMatchingStage(options, &database);
  EXPECT_TRUE(stats.approximate);
  EXPECT_EQ(stats.num_verified, 3u);
  for (const PairMatchStats& pair : stats.pairs) {
    for (const FeatureMatch& match : database.ReadMatches(pair.image_id1, pair.image_id2)) {
      EXPECT_TRUE(IsCorrect(pair.image_id1, pair.image_id2, match));
    }
  }

  Database smaller(dir_ / "smaller.db");
  MakeScene(&smaller, 3, 480, 20);  // 500.
  EXPECT_FALSE(RunMatchingStage(options, &smaller).approximate);
}

TEST_F(FeatureMatchingTest, ApproximateMatchingFindsEveryPointInItsCell) {
  Database database(dir_ / "database.db");
  MakeScene(&database, 4, 150, 60);
  MatchingStageOptions options;
  options.num_threads = 2;
  options.approximate.mode = ApproximateMatchingOptions::Mode::kOn;
  options.approximate.cells.num_cells = 8;
  options.approximate.cells.num_assignments = 2;
  const MatchingStageResult stats = RunMatchingStage(options, &database);
  EXPECT_TRUE(stats.approximate);
  EXPECT_EQ(stats.num_verified, 6u);
  for (const PairMatchStats& pair : stats.pairs) {
    // A point's descriptor is the same in every view, so it falls in the same cell: every
    // point is matched and nothing else, as the exact matcher does.
    EXPECT_EQ(pair.num_putative, 150);
    for (const FeatureMatch& match : database.ReadMatches(pair.image_id1, pair.image_id2)) {
      EXPECT_TRUE(IsCorrect(pair.image_id1, pair.image_id2, match));
    }
  }
}

}  // namespace
}  // namespace parallax
