#pragma once

#include <filesystem>
#include <memory>

#include "parallax/distributed/process_group.h"
#include "parallax/pipeline/matching_stage.h"

namespace parallax {

// Matching shared among the ranks of a process group: each rank matches blocks of the
// coordinator's pairs (consecutive pairs, which share images, so a block reuses the
// descriptors it loads), dealt round robin, into its shard database; the coordinator merges
// every shard in `shard_dir` into the run's database.
class ShardPairSharing : public PairSharing {
 public:
  // This rank's shard is `shard_dir`/rank-<rank>.db, opened when first needed and closed
  // while the coordinator merges, so that the file alone holds it.
  ShardPairSharing(const ProcessGroup& group, std::filesystem::path shard_dir);
  ~ShardPairSharing() override;

  bool IsCoordinator() const override { return group_.IsCoordinator(); }
  void Share(std::vector<std::pair<image_t, image_t>>* pairs,
             double choosing_seconds) const override;
  std::vector<std::pair<image_t, image_t>> ShareOf(
      const std::vector<std::pair<image_t, image_t>>& pairs) const override;
  Database* Store() override;
  std::vector<PairMatchStats> Merge(Database* database) override;
  // Pairs dealt to this rank so far.
  size_t NumPairsShared() const { return num_pairs_shared_; }
  // Seconds the coordinator spent choosing pairs and merging shards (the other ranks wait
  // meanwhile).
  double ChoosingSeconds() const { return choosing_seconds_; }
  double MergeSeconds() const { return merge_seconds_; }

 private:
  const ProcessGroup& group_;
  const std::filesystem::path shard_dir_;
  std::unique_ptr<Database> shard_;
  mutable size_t num_pairs_shared_ = 0;
  mutable double choosing_seconds_ = 0;
  double merge_seconds_ = 0;
};

// Pairs per block when `num_pairs` pairs are dealt to `num_ranks` ranks: about four blocks per
// rank, so that ranks finish close together, and at most 200 pairs, enough to reuse loaded
// descriptors.
size_t PairBlockSize(size_t num_pairs, int num_ranks);
// The blocks of `pairs` (PairBlockSize) that rank `rank` of `num_ranks` matches: every
// num_ranks-th block from its own, in order.
std::vector<std::pair<image_t, image_t>> PairsOfRank(
    const std::vector<std::pair<image_t, image_t>>& pairs, int rank, int num_ranks);

// Moves the matches and two-view geometries of every pair that `shard` holds and `database`
// does not into `database` (one transaction); returns their statistics.
std::vector<PairMatchStats> MergePairsFromShard(const Database& shard, Database* database);

}  // namespace parallax
