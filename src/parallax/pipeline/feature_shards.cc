#include "parallax/pipeline/feature_shards.h"

#include <algorithm>
#include <chrono>

#include "parallax/util/file.h"

namespace parallax {

FeatureShardIndex::FeatureShardIndex(const std::vector<std::filesystem::path>& shard_paths) {
  for (const std::filesystem::path& path : shard_paths) {
    shards_.push_back(std::make_unique<Database>(path));
    const Database& shard = *shards_.back();
    for (const Image& image : shard.ReadAllImages()) {
      if (entries_.count(image.name) > 0) continue;
      if (!shard.ExistsKeypoints(image.image_id) || !shard.ExistsDescriptors(image.image_id)) {
        continue;
      }
      const std::optional<ImageFileFingerprint> fingerprint =
          shard.ReadImageFileFingerprint(image.image_id);
      if (!fingerprint) continue;  // Shards are Parallax's own; they always have one.
      entries_[image.name] = Entry{shards_.size() - 1, image.image_id, *fingerprint};
    }
  }
}

FeatureShardIndex::~FeatureShardIndex() = default;

const FeatureShardIndex::Entry* FeatureShardIndex::CurrentEntry(
    const std::filesystem::path& path) const {
  const auto entry = entries_.find(path.filename().string());
  if (entry == entries_.end()) return nullptr;
  const std::optional<ImageFileFingerprint> now = StatImageFile(path);
  if (!now || now->size != entry->second.fingerprint.size ||
      now->mtime_ns != entry->second.fingerprint.mtime_ns) {
    return nullptr;
  }
  return &entry->second;
}

std::optional<ImageFileFingerprint> StatImageFile(const std::filesystem::path& path) {
  std::error_code error;
  ImageFileFingerprint fingerprint;
  fingerprint.size = static_cast<uint64_t>(std::filesystem::file_size(path, error));
  if (error) return std::nullopt;
  const auto mtime = std::filesystem::last_write_time(path, error);
  if (error) return std::nullopt;
  fingerprint.mtime_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(mtime.time_since_epoch()).count();
  return fingerprint;
}

bool FeatureShardIndex::Holds(const std::filesystem::path& path) const {
  return CurrentEntry(path) != nullptr;
}

std::optional<ShardImageFeatures> FeatureShardIndex::Find(const std::filesystem::path& path) const {
  const Entry* entry = CurrentEntry(path);
  if (entry == nullptr) return std::nullopt;
  const std::lock_guard<std::mutex> lock(mutex_);
  const Database& shard = *shards_[entry->shard];
  const image_t image_id = entry->image_id;
  ShardImageFeatures features;
  const Camera camera = shard.ReadCamera(shard.ReadImage(image_id).camera_id);
  features.width = camera.width;
  features.height = camera.height;
  features.keypoints = shard.ReadKeypoints(image_id);
  features.descriptors = shard.ReadDescriptors(image_id);
  features.colors = shard.ReadKeypointColors(image_id);
  features.fingerprint = entry->fingerprint;
  return features;
}

std::vector<std::filesystem::path> ListShardDatabases(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> paths;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("rank-", 0) == 0 && entry.path().extension() == ".db") {
      paths.push_back(entry.path());
    }
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

}  // namespace parallax
