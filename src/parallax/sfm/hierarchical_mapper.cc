#include "parallax/sfm/hierarchical_mapper.h"

#include <algorithm>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {

void HierarchicalMapperOptions::Check() const {
  partition.Check();
  merge.Check();
  PARALLAX_CHECK(num_threads == -1 || num_threads >= 1);
}

HierarchicalMapper::HierarchicalMapper(const HierarchicalMapperOptions& options,
                                       const IncrementalMapperOptions& mapper_options,
                                       const MapperInput& input)
    : options_(options), mapper_options_(mapper_options), input_(input) {
  options_.Check();
  mapper_options_.Check();
}

std::vector<std::vector<image_t>> HierarchicalMapper::Partition() const {
  std::vector<ViewGraphEdge> edges;
  for (const auto& [pair_id, geometry] : input_.two_view_geometries) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    edges.push_back({image_id1, image_id2, static_cast<double>(geometry.inlier_matches.size())});
  }
  return PartitionViewGraph(options_.partition, edges);
}

std::vector<Reconstruction> HierarchicalMapper::MapCluster(
    const std::vector<std::vector<image_t>>& clusters, size_t index, int num_side_by_side,
    ProgressReporter* progress, ClusterReport* report) const {
  PARALLAX_CHECK_LT(index, clusters.size());
  PARALLAX_CHECK(report != nullptr);
  Timer timer;
  const ImageCluster cluster = MakeImageCluster(input_, clusters[index]);
  const MapperInput part = ClusterMapperInput(input_, cluster, "cluster");
  IncrementalMapperOptions options = mapper_options_;
  for (BundleAdjustmentOptions* ba : options.BundleAdjustments()) {
    ba->num_threads = std::max(1, EffectiveNumThreads(ba->num_threads) / num_side_by_side);
  }
  options.seed = DeriveSeed(mapper_options_.seed, index);
  IncrementalMapper mapper(options, part);
  if (progress != nullptr) mapper.SetProgress(progress);
  MapperSummary cluster_summary;
  std::vector<Reconstruction> models = mapper.Reconstruct(&cluster_summary);
  report->num_images = cluster.image_names.size();
  report->num_pairs = cluster.pairs.size();
  report->model_sizes.clear();
  for (const Reconstruction& model : models) report->model_sizes.push_back(model.NumRegImages());
  report->seconds = timer.ElapsedSeconds();
  return models;
}

std::vector<Reconstruction> HierarchicalMapper::Reconstruct(
    const std::vector<std::vector<image_t>>& clusters, MapperSummary* summary,
    HierarchicalMapperSummary* hierarchical_summary) {
  PARALLAX_CHECK(summary != nullptr && hierarchical_summary != nullptr);
  HierarchicalMapperSummary report;
  report.clusters.resize(clusters.size());
  Timer timer;

  // 1. Map every cluster on its own.
  const int num_workers = std::max(
      1, std::min(EffectiveNumThreads(options_.num_threads), static_cast<int>(clusters.size())));
  size_t total_images = 0;
  for (const auto& cluster : clusters) total_images += cluster.size();
  PARALLAX_LOG(Info) << "mapper: " << clusters.size() << " clusters, " << total_images
                     << " images with the overlap, " << num_workers << " at a time";
  std::vector<std::vector<Reconstruction>> cluster_models(clusters.size());
  ProgressReporter progress("mapping clusters", total_images);
  ParallelFor(0, clusters.size(), num_workers, [&](size_t index) {
    cluster_models[index] =
        MapCluster(clusters, index, num_workers, &progress, &report.clusters[index]);
  });
  progress.Finish();
  report.cluster_seconds = timer.ElapsedSeconds();
  *hierarchical_summary = std::move(report);
  return MergeAndRefine(std::move(cluster_models), summary, hierarchical_summary);
}

std::vector<Reconstruction> HierarchicalMapper::MergeAndRefine(
    std::vector<std::vector<Reconstruction>> cluster_models, MapperSummary* summary,
    HierarchicalMapperSummary* hierarchical_summary) const {
  PARALLAX_CHECK(summary != nullptr && hierarchical_summary != nullptr);
  HierarchicalMapperSummary& report = *hierarchical_summary;
  PARALLAX_CHECK_EQ(report.clusters.size(), cluster_models.size());
  Timer timer;

  // 2. Merge the clusters' models into one frame.
  std::vector<Reconstruction> models;
  std::vector<std::pair<size_t, size_t>> origin;  // (cluster, model index) of each model.
  for (size_t index = 0; index < cluster_models.size(); ++index) {
    for (size_t k = 0; k < cluster_models[index].size(); ++k) {
      models.push_back(std::move(cluster_models[index][k]));
      origin.emplace_back(index, k);
    }
  }
  std::vector<ModelMergeReport> merges;
  // The merges draw from the mapping's one seed, as the clusters' registrations do.
  ModelMergerOptions merge_options = options_.merge;
  merge_options.seed = DeriveSeed(mapper_options_.seed, cluster_models.size());
  const Reconstruction merged = MergeModels(merge_options, models, &merges);
  for (size_t m = 0; m < models.size(); ++m) {
    report.clusters[origin[m].first].merges.push_back(merges[m]);
  }
  models.clear();
  report.merge_seconds = timer.ElapsedSeconds();
  PARALLAX_LOG(Info) << "mapper: clusters merged into one frame with " << merged.NumRegImages()
                     << " of " << input_.images.size() << " images";

  // 3. One model over everything, from the merged poses.
  timer.Restart();
  IncrementalMapper mapper(mapper_options_, input_);
  std::vector<Reconstruction> result =
      merged.NumRegImages() >= 2 ? mapper.Extend(merged, summary) : mapper.Reconstruct(summary);
  report.refine_seconds = timer.ElapsedSeconds();
  return result;
}

}  // namespace parallax
