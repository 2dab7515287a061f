#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "parallax/scene/database.h"

namespace parallax {

// The features of one image as a shard database holds them.
struct ShardImageFeatures {
  size_t width = 0;  // Of the image, from its camera in the shard.
  size_t height = 0;
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;
  std::optional<KeypointColors> colors;
  ImageFileFingerprint fingerprint;
};

// The shard databases of a distributed run (OUT/shards/rank-N.db, COLMAP schema), in which
// each rank stored the features of its share of the images; looked up by image file name.
// Thread safe: the extraction stage reads it from its workers.
class FeatureShardIndex {
 public:
  // Opens every shard; a name stored in several (a rerun with another number of ranks) is
  // taken from the first that holds its features.
  explicit FeatureShardIndex(const std::vector<std::filesystem::path>& shard_paths);
  ~FeatureShardIndex();

  // The features stored for the file at `path` (by its file name) when they were computed
  // from the file as it is now (same size and modification time); nullopt otherwise.
  std::optional<ShardImageFeatures> Find(const std::filesystem::path& path) const;
  // Whether Find would give them, without reading them.
  bool Holds(const std::filesystem::path& path) const;

 private:
  struct Entry {
    size_t shard = 0;
    image_t image_id = kInvalidImageId;
    ImageFileFingerprint fingerprint;
  };
  // The entry for the file at `path` when its size and modification time are the stored
  // ones; null otherwise.
  const Entry* CurrentEntry(const std::filesystem::path& path) const;

  std::vector<std::unique_ptr<Database>> shards_;
  std::map<std::string, Entry> entries_;
  mutable std::mutex mutex_;  // SQLite connections are used by one thread at a time.
};

// The size and modification time of the file at `path` as it is now (no digest); nullopt when
// either cannot be read. What the shard index and the extraction stage compare with the
// stored fingerprints.
std::optional<ImageFileFingerprint> StatImageFile(const std::filesystem::path& path);

// The shard databases in `dir` (rank-*.db), sorted by name.
std::vector<std::filesystem::path> ListShardDatabases(const std::filesystem::path& dir);

}  // namespace parallax
