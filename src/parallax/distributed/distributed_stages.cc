#include "parallax/distributed/distributed_stages.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>

#include "parallax/image/image_reader.h"
#include "parallax/pipeline/feature_shards.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/sfm/mapper_input.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

std::filesystem::path ShardPath(const std::filesystem::path& dir, int rank) {
  return dir / ("rank-" + std::to_string(rank) + ".db");
}

// Clusters as one flat list for a broadcast: count, then each cluster's size and ids.
std::vector<image_t> FlattenClusters(const std::vector<std::vector<image_t>>& clusters) {
  std::vector<image_t> flat{static_cast<image_t>(clusters.size())};
  for (const auto& cluster : clusters) {
    flat.push_back(static_cast<image_t>(cluster.size()));
    flat.insert(flat.end(), cluster.begin(), cluster.end());
  }
  return flat;
}

std::vector<std::vector<image_t>> UnflattenClusters(const std::vector<image_t>& flat) {
  PARALLAX_CHECK(!flat.empty());
  std::vector<std::vector<image_t>> clusters(flat[0]);
  size_t at = 1;
  for (auto& cluster : clusters) {
    PARALLAX_CHECK_LT(at, flat.size());
    const size_t size = flat[at++];
    PARALLAX_CHECK_LE(at + size, flat.size());
    cluster.assign(flat.begin() + at, flat.begin() + at + size);
    at += size;
  }
  return clusters;
}

// The images of a cluster, one id per line: a finished cluster's models are reused only for
// the same images.
std::string ClusterKey(const std::vector<image_t>& cluster) {
  std::ostringstream key;
  for (const image_t image_id : cluster) key << image_id << "\n";
  return key.str();
}

std::vector<Reconstruction> ReadClusterModels(const std::filesystem::path& dir) {
  std::vector<Reconstruction> models;
  for (size_t k = 0; std::filesystem::is_directory(dir / std::to_string(k)); ++k) {
    models.push_back(ReadReconstruction(dir / std::to_string(k)));
  }
  return models;
}

// Whether `dir` holds the finished models of a cluster of the same images (the key is
// written last, after the models).
bool ClusterIsFinished(const std::filesystem::path& dir, const std::string& key) {
  const std::filesystem::path key_path = dir / "images.txt";
  return std::filesystem::exists(key_path) && ReadFileToString(key_path) == key;
}

// The finished models of a cluster when `dir` holds them for the same images.
std::optional<std::vector<Reconstruction>> FinishedClusterModels(const std::filesystem::path& dir,
                                                                 const std::string& key) {
  if (!ClusterIsFinished(dir, key)) return std::nullopt;
  return ReadClusterModels(dir);
}

// Writes a cluster's models (binary) and its key into `dir`, atomically: beside it, then
// renamed, so a rank killed while writing leaves no half cluster.
void WriteClusterModels(const std::vector<Reconstruction>& models, const std::string& key,
                        const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  const fs::path staging = dir.string() + ".tmp";
  std::error_code error;
  fs::remove_all(staging, error);
  CreateDirectoryOrThrow(staging);
  for (size_t k = 0; k < models.size(); ++k) {
    CreateDirectoryOrThrow(staging / std::to_string(k));
    WriteReconstructionBinary(models[k], staging / std::to_string(k));
  }
  WriteTextFileAtomically(staging / "images.txt", key);
  fs::remove_all(dir, error);
  fs::rename(staging, dir, error);
  if (error) throw InputError(dir.string() + ": cannot rename into place: " + error.message());
}

// Bytes this process has read and written through system calls (rchar, wchar of
// /proc/self/io); zeros where that file does not exist.
std::pair<int64_t, int64_t> ProcessIoBytes() {
  std::ifstream io("/proc/self/io");
  std::string key;
  int64_t value = 0, read = 0, written = 0;
  while (io >> key >> value) {
    if (key == "rchar:") read = value;
    if (key == "wchar:") written = value;
  }
  return {read, written};
}

}  // namespace

std::vector<int> DealByCost(const std::vector<double>& costs, int num_ranks) {
  PARALLAX_CHECK_GT(num_ranks, 0);
  std::vector<size_t> order(costs.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&costs](size_t a, size_t b) { return costs[a] > costs[b]; });
  std::vector<double> load(num_ranks, 0.0);
  std::vector<int> owner(costs.size(), 0);
  for (const size_t item : order) {
    const int rank = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    owner[item] = rank;
    load[rank] += costs[item];
  }
  return owner;
}

DistributedStages::DistributedStages(const ProcessGroup& group, std::filesystem::path output_dir)
    : group_(group), output_dir_(std::move(output_dir)) {}

DistributedStages::~DistributedStages() = default;

std::filesystem::path DistributedStages::FeatureShardDir() const {
  return output_dir_ / "shards" / "features";
}

std::filesystem::path DistributedStages::PairShardDir() const {
  return output_dir_ / "shards" / "pairs";
}

ExtractionStageResult DistributedStages::Extract(const ExtractionStageOptions& options,
                                                 const CameraSetup& cameras,
                                                 const std::filesystem::path& image_dir,
                                                 Database* database) {
  CreateDirectoryOrThrow(FeatureShardDir());
  // 1. The coordinator deals out what neither the database nor a shard holds.
  std::string dealt;  // "rank<TAB>name" lines.
  if (group_.IsCoordinator()) {
    ExtractionStageOptions probe = options;
    probe.feature_shards = ListShardDatabases(FeatureShardDir());
    const std::vector<std::filesystem::path> paths = ImagesToExtract(probe, image_dir, database);
    std::vector<double> costs;
    for (const std::filesystem::path& path : paths) {
      const std::optional<ImageSize> size = ReadImageSize(path);
      costs.push_back(size ? static_cast<double>(size->width) * size->height : 0.0);
    }
    const std::vector<int> owners = DealByCost(costs, group_.Size());
    for (size_t k = 0; k < paths.size(); ++k) {
      dealt += std::to_string(owners[k]) + "\t" + paths[k].filename().string() + "\n";
    }
    PARALLAX_LOG(Info) << "features: " << paths.size() << " images to extract, dealt to "
                       << group_.Size() << " ranks by pixels";
  }
  group_.Broadcast(&dealt);

  // 2. Each rank extracts its share into its shard.
  ExtractionStageOptions share_options = options;
  share_options.forget_missing_images = false;
  share_options.feature_shards.clear();
  std::istringstream lines(dealt);
  std::string line;
  while (std::getline(lines, line)) {
    const size_t tab = line.find('\t');
    if (std::stoi(line.substr(0, tab)) == group_.Rank()) {
      share_options.only_images.push_back(line.substr(tab + 1));
    }
  }
  const Timer timer;
  ExtractionStageResult own;
  if (!share_options.only_images.empty()) {
    Database shard(ShardPath(FeatureShardDir(), group_.Rank()));
    own = RunExtractionStage(share_options, cameras, image_dir, &shard);
  }
  num_images_extracted_ += own.num_extracted;
  extraction_seconds_ += timer.ElapsedSeconds();
  group_.Barrier();

  // 3. The coordinator stores every image in name order from the shards.
  ExtractionStageResult merged;
  if (group_.IsCoordinator()) {
    const Timer merge_timer;
    ExtractionStageOptions merge_options = options;
    merge_options.feature_shards = ListShardDatabases(FeatureShardDir());
    merged = RunExtractionStage(merge_options, cameras, image_dir, database);
    num_images_total_ = merged.num_images_found;
    database->Checkpoint();  // For the ranks that read it next, maybe on other machines.
    feature_merge_seconds_ += merge_timer.ElapsedSeconds();
  }
  group_.Barrier();  // Nobody reads the database before the merge is in.
  return group_.IsCoordinator() ? merged : own;
}

std::vector<std::string> DistributedStages::RankReport() const {
  const auto [read, written] = ProcessIoBytes();
  const std::vector<std::vector<int64_t>> ranks =
      group_.GatherAll({static_cast<int64_t>(num_images_extracted_),
                        static_cast<int64_t>(pair_sharing_ ? pair_sharing_->NumPairsShared() : 0),
                        static_cast<int64_t>(num_clusters_mapped_), read, written,
                        static_cast<int64_t>(1000 * extraction_seconds_),
                        static_cast<int64_t>(1000 * cluster_seconds_)});
  std::vector<std::string> lines;
  if (!group_.IsCoordinator()) return lines;
  const double images = static_cast<double>(std::max<size_t>(1, num_images_total_));
  for (size_t rank = 0; rank < ranks.size(); ++rank) {
    const std::vector<int64_t>& r = ranks[rank];
    char line[320];
    std::snprintf(line, sizeof(line),
                  "rank %zu: %lld images extracted (%.1f s), %lld pairs matched, %lld clusters "
                  "mapped (%.1f s); read %.1f MB, wrote %.1f MB (%.2f and %.2f MB per image of "
                  "the run)",
                  rank, static_cast<long long>(r[0]), r[5] / 1000.0, static_cast<long long>(r[1]),
                  static_cast<long long>(r[2]), r[6] / 1000.0, r[3] / 1e6, r[4] / 1e6,
                  r[3] / 1e6 / images, r[4] / 1e6 / images);
    lines.emplace_back(line);
  }
  char line[240];
  std::snprintf(line, sizeof(line),
                "rank 0 alone: storing the features %.1f s, choosing pairs %.1f s, merging pairs "
                "%.1f s, merging and refining the clusters' models %.1f s",
                feature_merge_seconds_, pair_sharing_ ? pair_sharing_->ChoosingSeconds() : 0.0,
                pair_sharing_ ? pair_sharing_->MergeSeconds() : 0.0, model_merge_seconds_);
  lines.emplace_back(line);
  return lines;
}

PairSharing* DistributedStages::Pairs() {
  if (!pair_sharing_) {
    CreateDirectoryOrThrow(PairShardDir());
    pair_sharing_ = std::make_unique<ShardPairSharing>(group_, PairShardDir());
  }
  return pair_sharing_.get();
}

MappingStageResult DistributedStages::Map(const MappingStageOptions& options,
                                          const Database& database,
                                          const std::filesystem::path& image_dir,
                                          const std::filesystem::path& output_dir) {
  if (options.mapper_type == MapperType::kHierarchical) {
    return MapClusters(options, database, image_dir, output_dir);
  }
  // One incremental mapper: the coordinator's work alone.
  MappingStageResult result;
  if (group_.IsCoordinator()) result = RunMappingStage(options, database, image_dir, output_dir);
  group_.Barrier();
  return result;
}

MappingStageResult DistributedStages::MapClusters(const MappingStageOptions& options,
                                                  const Database& database,
                                                  const std::filesystem::path& image_dir,
                                                  const std::filesystem::path& output_dir) {
  options.Check();
  MappingStageResult result;
  result.mapper_type_reason = options.mapper_type_reason;
  Timer timer;
  // Every rank needs the whole input to cut its clusters from.
  const MapperInput input = LoadMapperInput(database, options.input);
  if (group_.IsCoordinator()) DescribeMapperInput(input, &result);
  result.load_seconds = timer.ElapsedSeconds();
  HierarchicalMapper mapper(options.hierarchical, options.mapper, input);

  // 1. The coordinator partitions; every rank gets the clusters.
  std::vector<image_t> flat;
  if (group_.IsCoordinator()) {
    const std::vector<std::vector<image_t>> clusters = mapper.Partition();
    WriteClusterFiles(input, clusters, output_dir / "clusters");
    flat = FlattenClusters(clusters);
  }
  group_.Broadcast(&flat);
  const std::vector<std::vector<image_t>> clusters = UnflattenClusters(flat);
  const std::filesystem::path models_dir = output_dir / "cluster_models";
  CreateDirectoryOrThrow(models_dir);

  // 2. Each rank maps the next cluster nobody has taken, until none is left.
  timer.Restart();
  {
    SharedCounter next_cluster(group_);
    for (int64_t index = next_cluster.Next(); index < static_cast<int64_t>(clusters.size());
         index = next_cluster.Next()) {
      const std::filesystem::path dir = models_dir / ("cluster-" + std::to_string(index));
      const std::string key = ClusterKey(clusters[index]);
      if (ClusterIsFinished(dir, key)) {
        PARALLAX_LOG(Info) << "mapper: cluster " << index << " mapped by an earlier run";
        continue;
      }
      ClusterReport report;
      const std::vector<Reconstruction> models =
          mapper.MapCluster(clusters, static_cast<size_t>(index), 1, nullptr, &report);
      WriteClusterModels(models, key, dir);
      ++num_clusters_mapped_;
      PARALLAX_LOG(Info) << "mapper: rank " << group_.Rank() << " mapped cluster " << index << " ("
                         << report.num_images << " images, " << report.seconds << " s)";
    }
    cluster_seconds_ += timer.ElapsedSeconds();
  }  // The counter's destruction waits for every rank.
  const double cluster_seconds = timer.ElapsedSeconds();

  // 3. The coordinator merges the clusters' models and refines.
  if (group_.IsCoordinator()) {
    const Timer merge_timer;
    std::vector<std::vector<Reconstruction>> cluster_models;
    result.hierarchical.emplace();
    for (size_t index = 0; index < clusters.size(); ++index) {
      const std::filesystem::path dir = models_dir / ("cluster-" + std::to_string(index));
      std::optional<std::vector<Reconstruction>> models =
          FinishedClusterModels(dir, ClusterKey(clusters[index]));
      PARALLAX_CHECK_MSG(models.has_value(), dir.string() + ": cluster models missing");
      ClusterReport report;
      report.num_images = clusters[index].size();
      for (const Reconstruction& model : *models)
        report.model_sizes.push_back(model.NumRegImages());
      result.hierarchical->clusters.push_back(report);
      cluster_models.push_back(std::move(*models));
    }
    result.hierarchical->cluster_seconds = cluster_seconds;
    result.models =
        mapper.MergeAndRefine(std::move(cluster_models), &result.summary, &*result.hierarchical);
    ColorizeAndWriteModels(options, &database, image_dir, output_dir, &result);
    model_merge_seconds_ += merge_timer.ElapsedSeconds();
  }
  group_.Barrier();
  return result;
}

}  // namespace parallax
