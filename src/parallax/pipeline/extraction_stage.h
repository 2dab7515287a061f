#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "parallax/feature/sift.h"
#include "parallax/image/image_reader.h"
#include "parallax/pipeline/camera_setup.h"
#include "parallax/scene/database.h"

namespace parallax {

struct ExtractionStageOptions {
  // The paper's detector (3 layers, edge 10, sigma 1.6) with contrast 0.02 (COLMAP's peak
  // threshold) instead of its 0.04, for longer tracks and smaller errors (docs/defaults.md,
  // "SIFT contrast 0.02").
  SiftExtractionOptions sift{.contrast_threshold = 0.02};
  ImageReaderOptions reader;  // Decoding limits.
  CameraSetupOptions camera;  // How cameras are assigned to images (LoadCameraSetup).
  int num_threads = -1;       // Images extracted in parallel; -1: all cores.
  // Images stored in the database whose file has left the folder (or is no longer an image)
  // are deleted from it with everything computed from them, so that no later stage uses
  // them. Off: they stay (a database shared by several folders).
  bool forget_missing_images = true;
  // Distributed runs (distributed/). A rank extracts only the images of these file names (its
  // share) into its shard database; empty: every image of the folder.
  std::vector<std::string> only_images;
  // The coordinator merges the shards: it takes the features of an image from these shard
  // databases when one holds them for the file as it is now (FeatureShardIndex) instead of
  // extracting them, and stores them exactly as it would its own.
  std::vector<std::filesystem::path> feature_shards;
  void Check() const;
};

struct ExtractionStageResult {
  size_t num_images_found = 0;  // Image files in the folder.
  size_t num_extracted = 0;     // Extracted and written in this run.
  size_t num_skipped = 0;       // Already in the database with features (resumed run).
  // (image name, reason) of files that could not be read or extracted, and of files named
  // like images (.jpg, .png, ...) that are not images by content.
  std::vector<std::pair<std::string, std::string>> failed;
  double mean_num_keypoints = 0;  // Over the images extracted in this run.
  double seconds = 0;
  // Thread time spent digesting files (new images, and stored ones whose size or
  // modification time changed).
  double hash_thread_seconds = 0;
};

// Stage 1: detects SIFT features in every image of `image_dir` (not recursive; files found
// by content) and writes image rows, keypoints and descriptors to `database`, one
// transaction per image, so a killed run resumes where it stopped: images already in the
// database with features are skipped, unless their file changed since (a different size or
// modification time, then a different XXH3 digest): those, and the pairs they are in, are
// computed again. After SIGINT or SIGTERM (util/interrupt.h) it stops once the images
// finished so far are stored, and throws Interrupted. Unreadable files are logged (one warning
// each) and skipped. Images are processed in parallel and written in name order, so image ids are
// deterministic. Throws InputError for a missing folder or intrinsics file, or a database
// that cannot be written.

// Cameras are assigned from `cameras` (LoadCameraSetup of options.camera, which the
// three-argument form loads itself).
ExtractionStageResult RunExtractionStage(const ExtractionStageOptions& options,
                                         const CameraSetup& cameras,
                                         const std::filesystem::path& image_dir,
                                         Database* database);
ExtractionStageResult RunExtractionStage(const ExtractionStageOptions& options,
                                         const std::filesystem::path& image_dir,
                                         Database* database);

// The image files of `image_dir` whose features neither `database` nor one of
// options.feature_shards holds for the file as it is now: what a run still has to extract.
// Name order. Brings stored fingerprints up to date as the stage does (a `touch`ed file).
std::vector<std::filesystem::path> ImagesToExtract(const ExtractionStageOptions& options,
                                                   const std::filesystem::path& image_dir,
                                                   Database* database);

}  // namespace parallax
