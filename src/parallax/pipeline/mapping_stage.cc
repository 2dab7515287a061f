#include "parallax/pipeline/mapping_stage.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <optional>
#include <vector>

#include "parallax/image/image_reader.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/sfm/point_triangulator.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {

void MappingStageOptions::Check() const {
  input.Check();
  mapper.Check();
  if (mapper_type == MapperType::kHierarchical) hierarchical.Check();
  PARALLAX_CHECK_MSG(cluster_file.empty() || mapper_type == MapperType::kIncremental,
                     "a cluster file is mapped by the incremental mapper");
  PARALLAX_CHECK_MSG(write_text || write_binary, "at least one model format must be written");
  PARALLAX_CHECK_MSG(input_model.empty() || mapper_type == MapperType::kIncremental,
                     "an input model is extended by the incremental mapper");
  PARALLAX_CHECK_MSG(!fixed_poses || !input_model.empty(), "fixed poses come from an input model");
}

void ColorizePoints(const std::filesystem::path& image_dir, const Database* database,
                    Reconstruction* reconstruction) {
  // Each image's colours come from the database when it stored those of the image's keypoints
  // (one per point2D), else from the image decoded (most of the time when it is, so images
  // run in parallel); their samples are summed in image order, so the colours do not depend
  // on the threads.
  const std::vector<image_t> image_ids = reconstruction->RegImageIds();
  std::vector<std::vector<std::pair<point3D_t, Eigen::Vector3d>>> samples(image_ids.size());
  std::mutex database_mutex;  // A Database is one thread's at a time.
  std::atomic<size_t> num_decoded = 0;
  ParallelFor(0, image_ids.size(), -1, [&](size_t index) {
    const Image& image = reconstruction->GetImage(image_ids[index]);
    std::optional<KeypointColors> stored;
    if (database != nullptr) {
      const std::lock_guard<std::mutex> lock(database_mutex);
      if (const std::optional<image_t> id = database->ImageIdByName(image.name)) {
        stored = database->ReadKeypointColors(*id);
      }
    }
    if (stored && stored->size() == 3 * image.points2D.size()) {
      for (size_t i = 0; i < image.points2D.size(); ++i) {
        const Point2D& point2D = image.points2D[i];
        if (!point2D.HasPoint3D()) continue;
        const uint8_t* rgb = stored->data() + 3 * i;
        samples[index].emplace_back(point2D.point3D_id, Eigen::Vector3d(rgb[0], rgb[1], rgb[2]));
      }
      return;
    }
    if (image_dir.empty()) return;  // No images given: the colours stay unset.
    Bitmap bitmap;
    try {
      bitmap = ReadBitmap(image_dir / image.name);
    } catch (const std::exception& error) {
      PARALLAX_LOG(Warning) << "colours: " << error.what();
      return;
    }
    ++num_decoded;
    for (const Point2D& point2D : image.points2D) {
      uint8_t rgb[3];
      if (!point2D.HasPoint3D() || !bitmap.RgbAt(point2D.xy.x(), point2D.xy.y(), rgb)) continue;
      samples[index].emplace_back(point2D.point3D_id, Eigen::Vector3d(rgb[0], rgb[1], rgb[2]));
    }
  });
  if (num_decoded > 0) {
    PARALLAX_LOG(Info) << "colours: " << num_decoded << " of " << image_ids.size()
                       << " images decoded again (the database holds no keypoint colours for "
                          "them)";
  }
  // Sums by point in a flat table (a tree insert per sample took seconds at 1,000 views);
  // each point's rank among the ids is its slot.
  std::vector<point3D_t> point3D_ids;
  point3D_ids.reserve(reconstruction->NumPoints3D());
  for (const auto& [point3D_id, point] : reconstruction->Points3D()) {
    point3D_ids.push_back(point3D_id);
  }
  std::vector<Eigen::Vector3d> color_sums(point3D_ids.size(), Eigen::Vector3d::Zero());
  std::vector<int> color_counts(point3D_ids.size(), 0);
  for (const auto& image_samples : samples) {
    for (const auto& [point3D_id, rgb] : image_samples) {
      const size_t slot =
          static_cast<size_t>(std::lower_bound(point3D_ids.begin(), point3D_ids.end(), point3D_id) -
                              point3D_ids.begin());
      color_sums[slot] += rgb;
      ++color_counts[slot];
    }
  }
  for (size_t slot = 0; slot < point3D_ids.size(); ++slot) {
    if (color_counts[slot] == 0) continue;
    const Eigen::Vector3d mean = color_sums[slot] / color_counts[slot];
    reconstruction->GetPoint3D(point3D_ids[slot]).color = mean.array().round().cast<uint8_t>();
  }
}

void WriteModels(const std::vector<Reconstruction>& models, const std::filesystem::path& output_dir,
                 bool write_text, bool write_binary) {
  namespace fs = std::filesystem;
  CreateDirectoryOrThrow(output_dir);
  // Leftovers of a run killed while writing.
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(output_dir, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("sparse.tmp-", 0) == 0 || name.rfind("sparse.old-", 0) == 0) {
      fs::remove_all(entry.path(), error);
    }
  }
  // The summary and point cloud of an earlier run go first, so that neither ever describes
  // models it did not come with (summary.json is written last, once everything is in place).
  for (const char* name : {"summary.json", "points.ply"}) fs::remove(output_dir / name, error);

  // All models are written beside sparse/ and then renamed into place: a run killed at any
  // moment leaves the earlier sparse/ or the new one, never a mix, and no model of an earlier
  // run with more models survives.
  const std::string suffix = std::to_string(static_cast<long>(getpid()));
  const fs::path staging = output_dir / ("sparse.tmp-" + suffix);
  try {
    for (size_t index = 0; index < models.size(); ++index) {
      const fs::path dir = staging / std::to_string(index);
      CreateDirectoryOrThrow(dir);
      // The two formats side by side: formatting the text files took longer than the rest of
      // the writing and colouring together (docs/performance.md,
      // "Models written in both formats side by side").
      ParallelFor(0, 2, /*num_threads=*/-1, [&](size_t format) {
        if (format == 0 && write_binary) WriteReconstructionBinary(models[index], dir);
        if (format == 1 && write_text) WriteReconstructionText(models[index], dir);
      });
    }
  } catch (...) {
    // A failed write (disk full) leaves the earlier sparse/ and nothing of its own.
    fs::remove_all(staging, error);
    throw;
  }
  const fs::path sparse = output_dir / "sparse";
  const fs::path previous = output_dir / ("sparse.old-" + suffix);
  if (fs::exists(sparse, error)) {
    fs::rename(sparse, previous, error);
    if (error) throw InputError(sparse.string() + ": cannot replace: " + error.message());
  }
  fs::rename(staging, sparse, error);
  if (error) throw InputError(sparse.string() + ": cannot rename into place: " + error.message());
  fs::remove_all(previous, error);
  if (!models.empty()) WritePointsPly(models.front(), output_dir / "points.ply");
}

void WriteClusterFiles(const MapperInput& input, const std::vector<std::vector<image_t>>& clusters,
                       const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::remove_all(dir, error);  // Clusters of an earlier partition would mislead.
  CreateDirectoryOrThrow(dir);
  for (size_t index = 0; index < clusters.size(); ++index) {
    WriteImageCluster(MakeImageCluster(input, clusters[index]),
                      dir / ("cluster-" + std::to_string(index) + ".txt"));
  }
}

MappingStageResult RunMappingStage(const MappingStageOptions& options, const Database& database,
                                   const std::filesystem::path& image_dir,
                                   const std::filesystem::path& output_dir) {
  options.Check();
  MappingStageResult result;
  result.mapper_type_reason = options.mapper_type_reason;
  Timer timer;
  // Read first: a missing or malformed model stops the stage before the database is loaded.
  std::optional<Reconstruction> input_model;
  if (!options.input_model.empty()) input_model = ReadReconstruction(options.input_model);
  MapperInput input = LoadMapperInput(database, options.input);
  if (!options.cluster_file.empty()) {
    const ImageCluster cluster = ReadImageCluster(options.cluster_file);
    input = ClusterMapperInput(input, cluster, options.cluster_file.string());
    PARALLAX_LOG(Info) << "mapper: cluster " << options.cluster_file.string() << ": "
                       << cluster.image_names.size() << " images, " << cluster.pairs.size()
                       << " pairs";
  }
  DescribeMapperInput(input, &result);
  result.load_seconds = timer.ElapsedSeconds();
  PARALLAX_LOG(Info) << "mapper: database loaded and tracks built in " << result.load_seconds
                     << " s";

  if (options.mapper_type == MapperType::kHierarchical) {
    HierarchicalMapper mapper(options.hierarchical, options.mapper, input);
    const std::vector<std::vector<image_t>> clusters = mapper.Partition();
    WriteClusterFiles(input, clusters, output_dir / "clusters");
    result.hierarchical.emplace();
    result.models = mapper.Reconstruct(clusters, &result.summary, &*result.hierarchical);
  } else if (input_model) {
    const Reconstruction seed =
        ModelInInputIds(*input_model, input, &result.input_model_images_missing);
    result.num_input_model_images = seed.NumRegImages();
    PARALLAX_LOG(Info) << "mapper: extending " << options.input_model.string() << ": "
                       << seed.NumRegImages() << " of its images keep their poses, "
                       << input.images.size() - seed.NumRegImages() << " others to register";
    if (!result.input_model_images_missing.empty()) {
      PARALLAX_LOG(Warning) << "mapper: " << result.input_model_images_missing.size()
                            << " images of " << options.input_model.string()
                            << " are no longer in the database and are left out (first: "
                            << result.input_model_images_missing.front() << ")";
    }
    if (options.fixed_poses) {
      result.models = {TriangulateIntoPoses(options.mapper, input, seed, &result.summary)};
    } else {
      IncrementalMapper mapper(options.mapper, input);
      result.models = mapper.Extend(seed, &result.summary);
    }
  } else {
    IncrementalMapper mapper(options.mapper, input);
    result.models = mapper.Reconstruct(&result.summary);
  }
  ColorizeAndWriteModels(options, &database, image_dir, output_dir, &result);
  return result;
}

void ColorizeAndWriteModels(const MappingStageOptions& options, const Database* database,
                            const std::filesystem::path& image_dir,
                            const std::filesystem::path& output_dir, MappingStageResult* result) {
  if (result->models.empty()) return;
  const Timer timer;
  for (Reconstruction& model : result->models) ColorizePoints(image_dir, database, &model);
  WriteModels(result->models, output_dir, options.write_text, options.write_binary);
  result->write_seconds = timer.ElapsedSeconds();
  PARALLAX_LOG(Info) << "mapper: models coloured and written in " << result->write_seconds << " s";
}

void DescribeMapperInput(const MapperInput& input, MappingStageResult* result) {
  for (const auto& [image_id, image] : input.images) {
    result->image_names[image_id] = image.name;
    result->num_keypoints[image_id] = image.points2D.size();
  }
  const auto& track_stats = input.correspondence_graph.Stats();
  PARALLAX_LOG(Info) << "mapper: " << input.images.size() << " images, "
                     << input.two_view_geometries.size() << " verified pairs, "
                     << track_stats.num_tracks << " tracks (mean length "
                     << track_stats.mean_track_length << ", " << track_stats.num_split_components
                     << " inconsistent components split)";
}

}  // namespace parallax
