#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "parallax/distributed/process_group.h"
#include "parallax/distributed/shard_pair_sharing.h"
#include "parallax/pipeline/reconstruction_pipeline.h"

namespace parallax {

// The stages of `parallax reconstruct` shared among the ranks of an MPI job, through shard
// databases on the filesystem that every rank sees (OUT/shards/):
//   1. features: the coordinator lists the images left to extract and deals them out by
//      estimated cost (pixels, largest first to the least loaded rank); each rank extracts its
//      share into OUT/shards/features/rank-N.db; the coordinator then stores them all in the
//      database in name order, as a one-process run would (same image and camera ids);
//   2. + 3. matching and verification: ShardPairSharing, shards OUT/shards/pairs/rank-N.db;
//   4. mapping: with the hierarchical mapper, the coordinator partitions the view graph, every
//      rank takes the next unmapped cluster as it frees up (a SharedCounter) and writes its
//      models to OUT/clusters/models/cluster-K/, and the coordinator merges them and runs the
//      final adjustment; with the incremental mapper the coordinator maps alone.
// What the shards and cluster folders hold survives a killed rank or job: a rerun of the
// same command skips it.
class DistributedStages : public StageSharing {
 public:
  DistributedStages(const ProcessGroup& group, std::filesystem::path output_dir);
  ~DistributedStages() override;

  bool IsCoordinator() const override { return group_.IsCoordinator(); }
  void Barrier() override { group_.Barrier(); }
  ExtractionStageResult Extract(const ExtractionStageOptions& options, const CameraSetup& cameras,
                                const std::filesystem::path& image_dir,
                                Database* database) override;
  PairSharing* Pairs() override;
  MappingStageResult Map(const MappingStageOptions& options, const Database& database,
                         const std::filesystem::path& image_dir,
                         const std::filesystem::path& output_dir) override;

  // What each rank did and the bytes it read and wrote (Linux /proc/self/io: every read and
  // write call, files and sockets, cached or not), one line per rank, on the coordinator;
  // empty elsewhere; then what the coordinator did alone. A collective call: every rank
  // makes it.
  std::vector<std::string> RankReport() const;

 private:
  std::filesystem::path FeatureShardDir() const;
  std::filesystem::path PairShardDir() const;
  // The hierarchical mapper's clusters mapped by every rank, merged by the coordinator.
  MappingStageResult MapClusters(const MappingStageOptions& options, const Database& database,
                                 const std::filesystem::path& image_dir,
                                 const std::filesystem::path& output_dir);

  const ProcessGroup& group_;
  const std::filesystem::path output_dir_;
  std::unique_ptr<ShardPairSharing> pair_sharing_;
  size_t num_images_total_ = 0;      // Image files of the run (the coordinator's count).
  size_t num_images_extracted_ = 0;  // By this rank.
  size_t num_clusters_mapped_ = 0;   // By this rank.
  double extraction_seconds_ = 0;    // This rank's share, before the merge.
  double cluster_seconds_ = 0;       // Mapping its clusters, before the merge.
  // The coordinator's work alone, while the other ranks wait: storing the features, merging
  // and refining the clusters' models (with writing the model).
  double feature_merge_seconds_ = 0;
  double model_merge_seconds_ = 0;
};

// Deals `costs` out to `num_ranks` ranks: largest first, each to the rank with the least cost
// so far (ties: the lower rank). Returns the rank of each item.
std::vector<int> DealByCost(const std::vector<double>& costs, int num_ranks);

}  // namespace parallax
