#include "parallax/sfm/hierarchical_mapper.h"

#include <gtest/gtest.h>

#include <set>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

Reconstruction LongSequence(double noise_px, uint64_t seed) {
  SyntheticDatasetOptions options;
  options.layout = SyntheticDatasetOptions::Layout::kSequence;
  options.num_images = 60;
  options.num_points3D = 6000;
  options.min_track_length = 3;
  options.point2D_noise_stddev = noise_px;
  options.seed = seed;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  return truth;
}

HierarchicalMapperOptions SmallClusters() {
  HierarchicalMapperOptions options;
  options.partition.max_cluster_images = 20;
  options.partition.overlap_images = 5;
  options.num_threads = 2;
  return options;
}

double SceneExtent(const Reconstruction& truth) {
  double extent = 0;
  for (const image_t a : truth.RegImageIds()) {
    for (const image_t b : truth.RegImageIds()) {
      extent = std::max(
          extent,
          (truth.GetImage(a).ProjectionCenter() - truth.GetImage(b).ProjectionCenter()).norm());
    }
  }
  return extent;
}

TEST(HierarchicalMapper, PartitionCoversEveryImageInOverlappingClusters) {
  const Reconstruction truth = LongSequence(0, 2);
  const MapperInput input = InputFromTruth(truth);
  HierarchicalMapper mapper(SmallClusters(), IncrementalMapperOptions(), input);
  const auto clusters = mapper.Partition();
  ASSERT_GE(clusters.size(), 3u);
  std::set<image_t> covered;
  for (const auto& cluster : clusters) {
    covered.insert(cluster.begin(), cluster.end());
    // At most 20 of its own, and 5 from each other cluster it borders.
    EXPECT_LE(cluster.size(), 20u + 5u * (clusters.size() - 1));
  }
  EXPECT_EQ(covered.size(), truth.NumImages());
}

TEST(HierarchicalMapper, PartitionedMappingRecoversThePoses) {
  const Reconstruction truth = LongSequence(0.5, 3);
  const MapperInput input = InputFromTruth(truth);
  HierarchicalMapper mapper(SmallClusters(), IncrementalMapperOptions(), input);
  const auto clusters = mapper.Partition();
  ASSERT_GE(clusters.size(), 3u);
  MapperSummary summary;
  HierarchicalMapperSummary hierarchical;
  const std::vector<Reconstruction> models = mapper.Reconstruct(clusters, &summary, &hierarchical);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].NumRegImages(), truth.NumImages());
  ASSERT_EQ(hierarchical.clusters.size(), clusters.size());
  for (size_t c = 0; c < clusters.size(); ++c) {
    const ClusterReport& report = hierarchical.clusters[c];
    EXPECT_EQ(report.num_images, clusters[c].size());
    ASSERT_FALSE(report.model_sizes.empty()) << "cluster " << c;
    EXPECT_EQ(report.model_sizes[0], clusters[c].size()) << "cluster " << c;
    ASSERT_EQ(report.merges.size(), report.model_sizes.size());
    EXPECT_TRUE(report.merges[0].success) << "cluster " << c;
  }
  for (const auto& [image_id, image_report] : summary.images)
    EXPECT_EQ(image_report.model_index, 0);
  Reconstruction copy = models[0];
  EXPECT_LT(copy.UpdatePointErrors(), 1.0);
  const PoseErrors errors = CompareToTruth(models[0], truth);
  EXPECT_LT(errors.max_center_error, 1e-3 * SceneExtent(truth));
  EXPECT_LT(errors.max_rotation_deg, 0.05);
}

TEST(HierarchicalMapper, SameResultWhicheverThreadMapsACluster) {
  const Reconstruction truth = LongSequence(0.5, 7);
  const MapperInput input = InputFromTruth(truth);
  HierarchicalMapperOptions options = SmallClusters();
  std::vector<Reconstruction> runs;
  for (const int num_threads : {1, 2}) {
    options.num_threads = num_threads;
    IncrementalMapperOptions mapper_options;
    for (BundleAdjustmentOptions* ba : mapper_options.BundleAdjustments()) ba->num_threads = 1;
    HierarchicalMapper mapper(options, mapper_options, input);
    MapperSummary summary;
    HierarchicalMapperSummary hierarchical;
    auto models = mapper.Reconstruct(mapper.Partition(), &summary, &hierarchical);
    ASSERT_FALSE(models.empty());
    runs.push_back(std::move(models[0]));
  }
  ASSERT_EQ(runs[0].NumRegImages(), runs[1].NumRegImages());
  for (const image_t image_id : runs[0].RegImageIds()) {
    EXPECT_EQ(runs[0].GetImage(image_id).cam_from_world.translation,
              runs[1].GetImage(image_id).cam_from_world.translation);
  }
}

}  // namespace
}  // namespace parallax
