#include "parallax/distributed/distributed_stages.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <numeric>
#include <set>
#include <thread>

#include "parallax/distributed/process_group.h"
#include "parallax/distributed/shard_pair_sharing.h"
#include "parallax/pipeline/feature_shards.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

using ImagePairs = std::vector<std::pair<image_t, image_t>>;

TEST(ProcessGroup, OutsideAnMpiJobIsThisProcessAlone) {
  if (StartedByMpiLauncher()) GTEST_SKIP() << "run under an MPI launcher";
  const ProcessGroup group;
  EXPECT_EQ(group.Rank(), 0);
  EXPECT_EQ(group.Size(), 1);
  EXPECT_TRUE(group.IsCoordinator());
  EXPECT_FALSE(group.IsDistributed());
  group.Barrier();
  std::string bytes = "kept";
  group.Broadcast(&bytes);
  EXPECT_EQ(bytes, "kept");
  std::vector<image_t> values = {3, 1, 2};
  group.Broadcast(&values);
  EXPECT_EQ(values, (std::vector<image_t>{3, 1, 2}));
  EXPECT_EQ(group.GatherAll({7, 8}), (std::vector<std::vector<int64_t>>{{7, 8}}));
  SharedCounter counter(group);
  EXPECT_EQ(counter.Next(), 0);
  EXPECT_EQ(counter.Next(), 1);
  EXPECT_EQ(counter.Next(), 2);
}

TEST(DealByCost, LargestFirstToTheLeastLoadedRank) {
  // Largest first: 9 -> 0, 8 -> 1, 5 -> 1 (8 < 9), 4 -> 0 (9 < 13), 1 -> 0 (13 = 13, lower).
  const std::vector<double> costs = {4, 9, 1, 8, 5};
  EXPECT_EQ(DealByCost(costs, 2), (std::vector<int>{0, 0, 0, 1, 1}));
  // Every item to some rank, loads within the largest item of each other.
  std::vector<double> many(101);
  for (size_t k = 0; k < many.size(); ++k) many[k] = static_cast<double>((k * 37) % 23 + 1);
  const std::vector<int> owners = DealByCost(many, 3);
  std::vector<double> load(3, 0.0);
  for (size_t k = 0; k < many.size(); ++k) {
    ASSERT_GE(owners[k], 0);
    ASSERT_LT(owners[k], 3);
    load[owners[k]] += many[k];
  }
  EXPECT_LE(
      *std::max_element(load.begin(), load.end()) - *std::min_element(load.begin(), load.end()),
      23.0);
  EXPECT_EQ(DealByCost(costs, 1), std::vector<int>(costs.size(), 0));
}

TEST(PairsOfRank, EveryPairToExactlyOneRankInBlocksOfConsecutivePairs) {
  ImagePairs pairs;
  for (image_t a = 1; a <= 30; ++a) {
    for (image_t b = a + 1; b <= 30; ++b) pairs.emplace_back(a, b);
  }
  for (const int num_ranks : {1, 2, 3, 7}) {
    std::multiset<std::pair<image_t, image_t>> seen;
    for (int rank = 0; rank < num_ranks; ++rank) {
      const ImagePairs share = PairsOfRank(pairs, rank, num_ranks);
      seen.insert(share.begin(), share.end());
      // A share keeps the coordinator's order, so a block's images stay together.
      for (size_t k = 1; k < share.size(); ++k) {
        EXPECT_LT(std::find(pairs.begin(), pairs.end(), share[k - 1]),
                  std::find(pairs.begin(), pairs.end(), share[k]));
      }
      if (num_ranks > 1) {
        EXPECT_LT(share.size(), pairs.size());
      }
    }
    const std::multiset<std::pair<image_t, image_t>> all(pairs.begin(), pairs.end());
    EXPECT_EQ(seen, all) << num_ranks << " ranks";
  }
  EXPECT_EQ(PairBlockSize(435, 3), 37u);
  EXPECT_EQ(PairBlockSize(1, 3), 1u);
  EXPECT_EQ(PairBlockSize(1000000, 3), 200u);
}

FeatureMatches Matches(int count, int offset) {
  FeatureMatches matches;
  for (int k = 0; k < count; ++k) {
    matches.push_back({static_cast<point2D_t>(k), static_cast<point2D_t>(k + offset)});
  }
  return matches;
}

TEST(MergePairsFromShard, MovesWhatTheDatabaseLacksAndKeepsWhatItHas) {
  const test::ScopedTestDir dir("parallax_merge_pairs");
  Database database(dir.path() / "database.db");
  Database shard(dir.path() / "rank-1.db");
  TwoViewGeometry verified;
  verified.config = TwoViewGeometry::kCalibrated;
  verified.inlier_matches = Matches(20, 1);
  verified.E(0, 1) = 1.0;
  TwoViewGeometry rejected;
  rejected.config = TwoViewGeometry::kDegenerate;
  shard.WriteMatches(1, 2, Matches(30, 1));
  shard.WriteTwoViewGeometry(1, 2, verified);
  shard.WriteMatches(1, 3, Matches(5, 2));
  shard.WriteTwoViewGeometry(1, 3, rejected);
  // Already in the database (merged before a kill): left as it is.
  TwoViewGeometry stored = verified;
  stored.inlier_matches = Matches(25, 3);
  database.WriteMatches(2, 3, Matches(40, 3));
  database.WriteTwoViewGeometry(2, 3, stored);
  shard.WriteMatches(2, 3, Matches(10, 4));
  shard.WriteTwoViewGeometry(2, 3, verified);
  // Matches stored without a geometry are not finished: not merged.
  shard.WriteMatches(3, 4, Matches(12, 1));

  const std::vector<PairMatchStats> merged = MergePairsFromShard(shard, &database);
  ASSERT_EQ(merged.size(), 2u);
  EXPECT_EQ(database.ReadMatches(1, 2), Matches(30, 1));
  EXPECT_EQ(database.ReadTwoViewGeometry(1, 2).inlier_matches, verified.inlier_matches);
  EXPECT_EQ(database.ReadTwoViewGeometry(1, 2).E, verified.E);
  EXPECT_EQ(database.ReadTwoViewGeometry(1, 3).config, TwoViewGeometry::kDegenerate);
  EXPECT_EQ(database.ReadTwoViewGeometry(2, 3).inlier_matches, Matches(25, 3));
  EXPECT_EQ(database.ReadMatches(2, 3), Matches(40, 3));
  EXPECT_FALSE(database.ExistsMatches(3, 4));
  for (const PairMatchStats& pair : merged) {
    if (pair.image_id2 == 2) {
      EXPECT_EQ(pair.num_putative, 30);
      EXPECT_EQ(pair.num_inliers, 20);
    } else {
      EXPECT_EQ(pair.num_putative, 5);
      EXPECT_EQ(pair.config, TwoViewGeometry::kDegenerate);
    }
  }
  // A second merge finds nothing new.
  EXPECT_TRUE(MergePairsFromShard(shard, &database).empty());
}

TEST(FeatureShardIndex, FindsFeaturesOnlyForTheFileAsItIsNow) {
  const test::ScopedTestDir dir("parallax_feature_shards");
  const fs::path image = dir.path() / "a.jpg";
  std::ofstream(image) << "not really a photo";
  const auto fingerprint_now = [&image] {
    ImageFileFingerprint fingerprint;
    fingerprint.size = fs::file_size(image);
    fingerprint.mtime_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               fs::last_write_time(image).time_since_epoch())
                               .count();
    fingerprint.content_hash = "0123456789abcdef0123456789abcdef";
    return fingerprint;
  };
  fs::create_directories(dir.path() / "shards");
  {
    Database shard(dir.path() / "shards" / "rank-0.db");
    const camera_t camera_id =
        shard.WriteCamera(Camera::Create(1, CameraModelId::kSimplePinhole, 500, 640, 480));
    FeatureKeypoints keypoints = {FeatureKeypoint(1.5f, 2.5f), FeatureKeypoint(3.5f, 4.5f)};
    FeatureDescriptors descriptors = FeatureDescriptors::Constant(2, 128, 7);
    shard.WriteImageWithFeatures("a.jpg", camera_id, keypoints, descriptors, fingerprint_now());
  }
  std::ofstream(dir.path() / "shards" / "notes.txt") << "not a shard";
  const std::vector<fs::path> shards = ListShardDatabases(dir.path() / "shards");
  ASSERT_EQ(shards.size(), 1u);

  {
    const FeatureShardIndex index(shards);
    const std::optional<ShardImageFeatures> found = index.Find(image);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->width, 640u);
    EXPECT_EQ(found->height, 480u);
    ASSERT_EQ(found->keypoints.size(), 2u);
    EXPECT_EQ(found->keypoints[1].x, 3.5f);
    EXPECT_EQ(found->descriptors.rows(), 2);
    EXPECT_EQ(found->descriptors(1, 127), 7);
    EXPECT_FALSE(index.Find(dir.path() / "b.jpg").has_value());
    EXPECT_TRUE(index.Holds(image));
    EXPECT_FALSE(index.Holds(dir.path() / "b.jpg"));
  }
  // Another photo under the same name: the shard's features are not for it.
  std::ofstream(image, std::ios::app) << " with more bytes";
  EXPECT_FALSE(FeatureShardIndex(shards).Find(image).has_value());
  EXPECT_FALSE(FeatureShardIndex(shards).Holds(image));
}

}  // namespace
}  // namespace parallax
