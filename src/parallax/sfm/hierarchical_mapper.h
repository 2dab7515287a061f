#pragma once

#include <vector>

#include "parallax/util/progress.h"

#include "parallax/sfm/image_cluster.h"
#include "parallax/sfm/incremental_mapper.h"
#include "parallax/sfm/model_merger.h"
#include "parallax/sfm/view_graph_partition.h"

namespace parallax {

struct HierarchicalMapperOptions {
  ViewGraphPartitionOptions partition;
  ModelMergerOptions merge;
  // Clusters mapped at once (-1: one per core). Bundle adjustment inside a cluster gets the
  // remaining share of its thread count.
  int num_threads = -1;
  void Check() const;
};

// What happened to one cluster.
struct ClusterReport {
  size_t num_images = 0;
  size_t num_pairs = 0;
  std::vector<size_t> model_sizes;       // Registered images of each model it gave, largest first.
  std::vector<ModelMergeReport> merges;  // One per model, in the same order.
  double seconds = 0;
};

struct HierarchicalMapperSummary {
  std::vector<ClusterReport> clusters;
  double cluster_seconds = 0;  // Mapping all clusters (wall clock).
  double merge_seconds = 0;
  double refine_seconds = 0;  // Triangulating all tracks, registering leftovers, global BA.
};

// Partitioned mapping for large scenes: the view graph (weighted by verified matches) is cut
// into overlapping clusters, each mapped by the incremental mapper (clusters side by side),
// the clusters' models merged by similarities estimated from their shared images, and the
// merged poses handed to the incremental mapper over the whole input, which triangulates all
// tracks, registers what no cluster could, and finishes with global bundle adjustment.
// Cluster k's mapper seeds its RANSAC from the mapper's seed and k, so the result does not
// depend on which thread maps which cluster.
class HierarchicalMapper {
 public:
  HierarchicalMapper(const HierarchicalMapperOptions& options,
                     const IncrementalMapperOptions& mapper_options, const MapperInput& input);

  // The clusters the partition gives (ids of the input), for cluster files.
  std::vector<std::vector<image_t>> Partition() const;

  // Maps the clusters (Partition()), merges and refines. `summary` describes the final
  // stage, as the incremental mapper's does.
  std::vector<Reconstruction> Reconstruct(const std::vector<std::vector<image_t>>& clusters,
                                          MapperSummary* summary,
                                          HierarchicalMapperSummary* hierarchical_summary);

  // The two halves of Reconstruct, for a run whose clusters are mapped by other processes
  // (distributed/). Maps cluster `index` of `clusters` with the incremental mapper (seeded
  // from the mapper's seed and `index`); with `num_side_by_side` clusters mapped at once on
  // this machine, each bundle adjustment gets that share of its threads. `progress` may be
  // null.
  std::vector<Reconstruction> MapCluster(const std::vector<std::vector<image_t>>& clusters,
                                         size_t index, int num_side_by_side,
                                         ProgressReporter* progress, ClusterReport* report) const;
  // Merges the clusters' models (one list per cluster, in cluster order) and refines the
  // result over the whole input. `hierarchical_summary->clusters` holds one report per cluster.
  std::vector<Reconstruction> MergeAndRefine(
      std::vector<std::vector<Reconstruction>> cluster_models, MapperSummary* summary,
      HierarchicalMapperSummary* hierarchical_summary) const;

 private:
  const HierarchicalMapperOptions options_;
  const IncrementalMapperOptions mapper_options_;
  const MapperInput& input_;
};

}  // namespace parallax
