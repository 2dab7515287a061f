#include "parallax/distributed/shard_pair_sharing.h"

#include <algorithm>

#include "parallax/pipeline/feature_shards.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/timer.h"

namespace parallax {

size_t PairBlockSize(size_t num_pairs, int num_ranks) {
  PARALLAX_CHECK_GT(num_ranks, 0);
  const size_t blocks = 4 * static_cast<size_t>(num_ranks);
  return std::clamp<size_t>((num_pairs + blocks - 1) / blocks, 1, 200);
}

ShardPairSharing::ShardPairSharing(const ProcessGroup& group, std::filesystem::path shard_dir)
    : group_(group), shard_dir_(std::move(shard_dir)) {}

ShardPairSharing::~ShardPairSharing() = default;

Database* ShardPairSharing::Store() {
  if (!shard_) {
    shard_ =
        std::make_unique<Database>(shard_dir_ / ("rank-" + std::to_string(group_.Rank()) + ".db"));
  }
  return shard_.get();
}

void ShardPairSharing::Share(std::vector<std::pair<image_t, image_t>>* pairs,
                             double choosing_seconds) const {
  choosing_seconds_ += choosing_seconds;
  std::vector<image_t> flat;
  for (const auto& [image_id1, image_id2] : *pairs) {
    flat.push_back(image_id1);
    flat.push_back(image_id2);
  }
  group_.Broadcast(&flat);
  pairs->clear();
  for (size_t k = 0; k + 1 < flat.size(); k += 2) pairs->emplace_back(flat[k], flat[k + 1]);
}

std::vector<std::pair<image_t, image_t>> PairsOfRank(
    const std::vector<std::pair<image_t, image_t>>& pairs, int rank, int num_ranks) {
  PARALLAX_CHECK(rank >= 0 && rank < num_ranks);
  const size_t block_size = PairBlockSize(pairs.size(), num_ranks);
  std::vector<std::pair<image_t, image_t>> share;
  for (size_t start = 0, block = 0; start < pairs.size(); start += block_size, ++block) {
    if (static_cast<int>(block % num_ranks) != rank) continue;
    const size_t end = std::min(pairs.size(), start + block_size);
    share.insert(share.end(), pairs.begin() + start, pairs.begin() + end);
  }
  return share;
}

std::vector<std::pair<image_t, image_t>> ShardPairSharing::ShareOf(
    const std::vector<std::pair<image_t, image_t>>& pairs) const {
  std::vector<std::pair<image_t, image_t>> share = PairsOfRank(pairs, group_.Rank(), group_.Size());
  num_pairs_shared_ += share.size();
  return share;
}

std::vector<PairMatchStats> MergePairsFromShard(const Database& shard, Database* database) {
  std::vector<PairMatchStats> merged;
  DatabaseTransaction transaction(database);
  for (const auto& [pair_id, geometry] : shard.ReadTwoViewGeometries()) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    if (database->ExistsTwoViewGeometry(image_id1, image_id2)) continue;
    PairMatchStats stats;
    stats.image_id1 = image_id1;
    stats.image_id2 = image_id2;
    if (shard.ExistsMatches(image_id1, image_id2)) {
      const FeatureMatches matches = shard.ReadMatches(image_id1, image_id2);
      stats.num_putative = static_cast<int>(matches.size());
      if (!database->ExistsMatches(image_id1, image_id2)) {
        database->WriteMatches(image_id1, image_id2, matches);
      }
    }
    database->WriteTwoViewGeometry(image_id1, image_id2, geometry);
    stats.num_inliers = static_cast<int>(geometry.inlier_matches.size());
    stats.config = geometry.config;
    merged.push_back(stats);
  }
  transaction.Commit();
  return merged;
}

std::vector<PairMatchStats> ShardPairSharing::Merge(Database* database) {
  shard_.reset();  // Closing checkpoints it: the file alone holds what this rank stored.
  group_.Barrier();
  std::vector<PairMatchStats> merged;
  if (group_.IsCoordinator()) {
    const Timer timer;
    for (const std::filesystem::path& path : ListShardDatabases(shard_dir_)) {
      const Database shard(path);
      std::vector<PairMatchStats> from_shard = MergePairsFromShard(shard, database);
      merged.insert(merged.end(), from_shard.begin(), from_shard.end());
    }
    std::sort(merged.begin(), merged.end(), [](const PairMatchStats& a, const PairMatchStats& b) {
      return std::tie(a.image_id1, a.image_id2) < std::tie(b.image_id1, b.image_id2);
    });
    if (!merged.empty()) {
      database->Checkpoint();  // For the ranks that read it next, maybe on other machines.
      PARALLAX_LOG(Info) << "Matching: " << merged.size() << " pairs merged from the shards in "
                         << shard_dir_.string() << " (" << timer.ElapsedSeconds() << " s)";
    }
    merge_seconds_ += timer.ElapsedSeconds();
  }
  group_.Barrier();  // Nobody reads the database before the merge is in.
  return merged;
}

}  // namespace parallax
