#include "parallax/pipeline/extraction_stage.h"

#include <memory>
#include <opencv2/core.hpp>
#include <set>

#include "parallax/pipeline/feature_shards.h"
#include "parallax/util/check.h"
#include "parallax/util/content_hash.h"
#include "parallax/util/in_order_consumer.h"
#include "parallax/util/interrupt.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

// Sets OpenCV's thread count to one (when `single`) and restores it when the scope ends,
// also when the extraction loop throws.
class OpenCvThreadsGuard {
 public:
  explicit OpenCvThreadsGuard(bool single) : saved_(cv::getNumThreads()) {
    if (single) cv::setNumThreads(1);
  }
  ~OpenCvThreadsGuard() { cv::setNumThreads(saved_); }
  OpenCvThreadsGuard(const OpenCvThreadsGuard&) = delete;
  OpenCvThreadsGuard& operator=(const OpenCvThreadsGuard&) = delete;

 private:
  const int saved_;
};

// One image to extract: its file, database name and row (when the row exists already but
// its features do not, e.g. a database prepared by another tool).
struct ExtractionJob {
  std::filesystem::path path;
  std::string name;
  std::optional<image_t> image_id;
};

struct ExtractionResult {
  std::string error;  // Empty on success.
  size_t width = 0;
  size_t height = 0;
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;
  // Nullopt when a keypoint is not finite (the model's colours then come from the image) or
  // a shard stored none.
  std::optional<KeypointColors> colors;
  ImageFileFingerprint fingerprint;
  // Read once here, in parallel: the GPS position and, when EXIF tells cameras, the camera.
  std::optional<ExifData> exif;
  double hash_seconds = 0;
};

// The EXIF GPS position of a photo, if any.
std::optional<GeodeticPosition> GpsPosition(const std::optional<ExifData>& exif) {
  if (!exif || !exif->gps_latitude || !exif->gps_longitude) return std::nullopt;
  return GeodeticPosition{*exif->gps_latitude, *exif->gps_longitude,
                          exif->gps_altitude.value_or(0.0)};
}

// The colour under each keypoint (Bitmap::RgbAt), or nullopt when one has none.
std::optional<KeypointColors> SampleKeypointColors(const Bitmap& bitmap,
                                                   const FeatureKeypoints& keypoints) {
  KeypointColors colors(3 * keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    if (!bitmap.RgbAt(keypoints[i].x, keypoints[i].y, colors.data() + 3 * i)) return std::nullopt;
  }
  return colors;
}

// Size and modification time of the file as it is now (no digest).
ImageFileFingerprint StatImageFileOrThrow(const std::filesystem::path& path) {
  const std::optional<ImageFileFingerprint> fingerprint = StatImageFile(path);
  if (!fingerprint) {
    throw InputError(path.string() + ": cannot read the file's size or modification time");
  }
  return *fingerprint;
}

// The fingerprint with its digest; adds the time spent to `*hash_seconds`.
ImageFileFingerprint FingerprintImageFile(const std::filesystem::path& path, double* hash_seconds) {
  const Timer timer;
  ImageFileFingerprint fingerprint = StatImageFileOrThrow(path);
  fingerprint.content_hash = HashFile(path);
  *hash_seconds += timer.ElapsedSeconds();
  return fingerprint;
}

// Whether the features stored for `image_id` were computed from the file at `path` as it is
// now. Size and modification time decide when both match; otherwise the digest does (a copy
// with a new time, `touch`), and the stored fingerprint is brought up to date. Images stored
// without a fingerprint (by COLMAP, or an older Parallax) are taken as current and get one.
bool StoredFeaturesAreCurrent(image_t image_id, const std::filesystem::path& path,
                              Database* database, ExtractionStageResult* stats) {
  const std::optional<ImageFileFingerprint> stored = database->ReadImageFileFingerprint(image_id);
  const ImageFileFingerprint now = StatImageFileOrThrow(path);
  if (stored && stored->size == now.size && stored->mtime_ns == now.mtime_ns) return true;
  const ImageFileFingerprint hashed = FingerprintImageFile(path, &stats->hash_thread_seconds);
  if (stored && stored->content_hash != hashed.content_hash) return false;
  database->WriteImageFileFingerprint(image_id, hashed);
  return true;
}

ExtractionResult ExtractImage(const ExtractionJob& job, const ExtractionStageOptions& options,
                              const FeatureExtractor& extractor, const FeatureShardIndex* shards) {
  ExtractionResult result;
  try {
    if (std::optional<ShardImageFeatures> stored = shards ? shards->Find(job.path) : std::nullopt) {
      // Extracted by another rank of a distributed run: stored here as if extracted here.
      result.fingerprint = std::move(stored->fingerprint);
      result.width = stored->width;
      result.height = stored->height;
      result.keypoints = std::move(stored->keypoints);
      result.descriptors = std::move(stored->descriptors);
      result.colors = std::move(stored->colors);
      result.exif = ReadExifHint(job.path);
      return result;
    }
    result.fingerprint = FingerprintImageFile(job.path, &result.hash_seconds);
    const Bitmap bitmap = ReadBitmap(job.path, options.reader);
    result.width = static_cast<size_t>(bitmap.Width());
    result.height = static_cast<size_t>(bitmap.Height());
    extractor.Extract(bitmap.gray, &result.keypoints, &result.descriptors);
    result.colors = SampleKeypointColors(bitmap, result.keypoints);
    result.exif = ReadExifHint(job.path);
  } catch (const CheckError&) {
    throw;  // A bug, not a bad file.
  } catch (const std::exception& error) {
    // ReadBitmap's InputError already starts with the path; OpenCV's errors do not.
    const std::string message = error.what();
    result.error =
        message.rfind(job.path.string(), 0) == 0 ? message : job.path.string() + ": " + message;
  }
  return result;
}

}  // namespace

void ExtractionStageOptions::Check() const {
  sift.Check();
  reader.Check();
  camera.Check();
  PARALLAX_CHECK_MSG(only_images.empty() || !forget_missing_images,
                     "a share of the images must not forget the others");
}

std::vector<std::filesystem::path> ImagesToExtract(const ExtractionStageOptions& options,
                                                   const std::filesystem::path& image_dir,
                                                   Database* database) {
  PARALLAX_CHECK(database != nullptr);
  const std::optional<FeatureShardIndex> shards =
      options.feature_shards.empty()
          ? std::nullopt
          : std::make_optional<FeatureShardIndex>(options.feature_shards);
  ExtractionStageResult unused;
  std::vector<std::filesystem::path> to_extract;
  for (const std::filesystem::path& path : ListImageFiles(image_dir)) {
    const std::optional<image_t> image_id = database->ImageIdByName(path.filename().string());
    if (image_id && database->ExistsKeypoints(*image_id) &&
        database->ExistsDescriptors(*image_id) &&
        StoredFeaturesAreCurrent(*image_id, path, database, &unused)) {
      continue;
    }
    if (shards && shards->Holds(path)) continue;
    to_extract.push_back(path);
  }
  return to_extract;
}

ExtractionStageResult RunExtractionStage(const ExtractionStageOptions& options,
                                         const std::filesystem::path& image_dir,
                                         Database* database) {
  // A setting no image can satisfy would otherwise skip every image with the same warning.
  return RunExtractionStage(options, LoadCameraSetup(options.camera), image_dir, database);
}

ExtractionStageResult RunExtractionStage(const ExtractionStageOptions& options,
                                         const CameraSetup& cameras,
                                         const std::filesystem::path& image_dir,
                                         Database* database) {
  options.Check();
  PARALLAX_CHECK(database != nullptr);
  const Timer timer;
  ExtractionStageResult stats;

  std::vector<RejectedImageFile> rejected;
  std::vector<std::filesystem::path> paths = ListImageFiles(image_dir, &rejected);
  if (!options.only_images.empty()) {
    const std::set<std::string> share(options.only_images.begin(), options.only_images.end());
    std::erase_if(paths, [&share](const std::filesystem::path& path) {
      return share.count(path.filename().string()) == 0;
    });
    std::erase_if(rejected, [&share](const RejectedImageFile& file) {
      return share.count(file.path.filename().string()) == 0;
    });
  }
  stats.num_images_found = paths.size();
  // Named like images but not images: the user probably expects them used, so say why not.
  for (const RejectedImageFile& file : rejected) {
    const std::string message = file.path.string() + ": " + file.reason;
    PARALLAX_LOG(Warning) << "skipping " << message;
    stats.failed.emplace_back(file.path.filename().string(), message);
  }
  CameraAssigner camera_assigner(cameras, database);

  std::set<std::string> names_in_folder;
  std::vector<ExtractionJob> jobs;
  for (const std::filesystem::path& path : paths) {
    ExtractionJob job{path, path.filename().string(),
                      database->ImageIdByName(path.filename().string())};
    names_in_folder.insert(job.name);
    if (job.image_id && database->ExistsKeypoints(*job.image_id) &&
        database->ExistsDescriptors(*job.image_id)) {
      if (StoredFeaturesAreCurrent(*job.image_id, path, database, &stats)) {
        ++stats.num_skipped;
        continue;
      }
      // Another photo under the same name: nothing stored for it may be reused.
      PARALLAX_LOG(Warning) << path.string()
                            << ": changed since its features were stored; extracting it again "
                               "and matching it again with every image";
      database->DeleteImage(*job.image_id);
      job.image_id.reset();
    }
    jobs.push_back(std::move(job));
  }
  if (options.forget_missing_images) {
    for (const Image& image : database->ReadAllImages()) {
      if (names_in_folder.count(image.name) > 0) continue;
      PARALLAX_LOG(Warning) << (image_dir / image.name).string()
                            << ": in the database but no longer an image of the folder; left "
                               "out, its features and matches deleted";
      database->DeleteImage(image.image_id);
    }
  }
  PARALLAX_LOG(Info) << "Feature extraction: " << paths.size() << " images in "
                     << image_dir.string() << ", " << stats.num_skipped
                     << " already in the database, " << jobs.size() << " to extract";

  size_t total_keypoints = 0;
  ProgressReporter progress("features", jobs.size());

  const auto write_result = [&](size_t index, const ExtractionResult& result) {
    const ExtractionJob& job = jobs[index];
    if (!result.error.empty()) {
      PARALLAX_LOG(Warning) << "skipping " << result.error;
      stats.failed.emplace_back(job.name, result.error);
      return;
    }
    if (job.image_id) {
      // The row exists; add what is missing (each write is atomic on its own).
      if (!database->ExistsKeypoints(*job.image_id)) {
        database->WriteKeypoints(*job.image_id, result.keypoints);
        if (result.colors) database->WriteKeypointColors(*job.image_id, *result.colors);
      }
      if (!database->ExistsDescriptors(*job.image_id)) {
        database->WriteDescriptors(*job.image_id, result.descriptors);
      }
    } else {
      camera_t camera_id = kInvalidCameraId;
      try {
        const ImageCameraInfo info =
            camera_assigner.UsesExif() && result.exif
                ? ImageCameraInfoFromExif(*result.exif, result.width, result.height,
                                          cameras.options.sensor_width_mm)
                : ImageCameraInfo{};
        camera_id =
            camera_assigner.CameraForImage(job.path.string(), result.width, result.height, info);
      } catch (const InputError& error) {
        PARALLAX_LOG(Warning) << "skipping " << error.what();
        stats.failed.emplace_back(job.name, error.what());
        return;
      }
      database->WriteImageWithFeatures(job.name, camera_id, result.keypoints, result.descriptors,
                                       result.fingerprint, GpsPosition(result.exif), result.colors);
    }
    if (job.image_id) database->WriteImageFileFingerprint(*job.image_id, result.fingerprint);
    stats.hash_thread_seconds += result.hash_seconds;
    ++stats.num_extracted;
    total_keypoints += result.keypoints.size();
    if (result.keypoints.empty()) {
      // Stored all the same (a resumed run skips it), but it can never be registered.
      PARALLAX_LOG(Warning) << job.path.string()
                            << ": no features found (blank or textureless image); it cannot "
                               "be registered";
    }
    PARALLAX_LOG(Debug) << job.name << ": " << result.keypoints.size() << " keypoints";
  };

  // Images are extracted in parallel, so OpenCV's own threads inside SIFT only compete with
  // ours, and its pool busy-waits after each call, which slowed the mapping stage that
  // follows (docs/performance.md, "One OpenCV thread while every worker has an image"). One OpenCV
  // thread while there is an image per worker.
  const std::optional<FeatureShardIndex> shards =
      options.feature_shards.empty()
          ? std::nullopt
          : std::make_optional<FeatureShardIndex>(options.feature_shards);
  {
    const OpenCvThreadsGuard opencv_threads(
        /*single=*/jobs.size() >= static_cast<size_t>(EffectiveNumThreads(options.num_threads)));
    // One extractor for the stage: it keeps its buffers between images, and frees them here.
    const std::unique_ptr<FeatureExtractor> extractor = CreateSiftExtractor(options.sift);
    // Results are written in job order (deterministic image ids), one transaction per image,
    // by a thread of their own: SQLite's checkpoints fsync, and a worker that wrote would
    // wait for them (docs/performance.md, "Extraction results written by a thread of their own").
    InOrderConsumer<ExtractionResult> writer(jobs.size(),
                                             [&](size_t index, const ExtractionResult& result) {
                                               write_result(index, result);
                                               progress.Increment();
                                             });
    ParallelFor(0, jobs.size(), options.num_threads, [&](size_t index) {
      // After a signal (or a failed write) no new image starts; those finished are written
      // in order up to the first that did not run.
      if (PendingInterruptSignal() != 0 || writer.Failed()) return;
      writer.Put(index,
                 ExtractImage(jobs[index], options, *extractor, shards ? &*shards : nullptr));
    });
    writer.Finish();
  }
  progress.Finish();
  ThrowIfInterrupted("features of " + std::to_string(stats.num_skipped + stats.num_extracted) +
                     " of " + std::to_string(paths.size()) + " images are stored in " +
                     database->Path().string());

  stats.mean_num_keypoints =
      stats.num_extracted > 0 ? static_cast<double>(total_keypoints) / stats.num_extracted : 0.0;
  stats.seconds = timer.ElapsedSeconds();
  PARALLAX_LOG(Info) << "Feature extraction: " << stats.num_extracted << " extracted, "
                     << stats.num_skipped << " skipped, " << stats.failed.size() << " failed, mean "
                     << static_cast<long>(stats.mean_num_keypoints + 0.5) << " keypoints, "
                     << stats.seconds << " s (digests " << stats.hash_thread_seconds
                     << " s thread time)";
  return stats;
}

}  // namespace parallax
