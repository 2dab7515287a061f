#include "parallax/pipeline/reconstruction_pipeline.h"

#include "parallax/image/image_reader.h"
#include "parallax/report/ground_truth.h"
#include "parallax/report/html_report.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"
#include "parallax/util/run_lock.h"
#include "parallax/util/timer.h"

namespace parallax {

void ReconstructionPipelineOptions::Check() const {
  extraction.Check();
  matching.Check();
  mapping.Check();
}

void SetSeed(uint64_t seed, ReconstructionPipelineOptions* options) {
  options->matching.seed = seed;
  options->mapping.mapper.seed = seed;
}

void SetSeedAndThreads(uint64_t seed, int num_threads, bool keep_ba_threads,
                       ReconstructionPipelineOptions* options) {
  SetSeed(seed, options);
  options->extraction.num_threads = num_threads;
  options->matching.num_threads = num_threads;
  options->mapping.hierarchical.num_threads = num_threads;
  if (keep_ba_threads) return;
  for (BundleAdjustmentOptions* ba : options->mapping.mapper.BundleAdjustments()) {
    ba->num_threads = num_threads;
  }
}

ReconstructionPipelineResult RunReconstructionPipeline(const ReconstructionPipelineOptions& options,
                                                       const std::filesystem::path& image_dir,
                                                       const std::filesystem::path& output_dir,
                                                       StageSharing* sharing) {
  options.Check();
  if (!std::filesystem::is_directory(image_dir)) {
    throw MissingFileError(image_dir.string() + ": image folder does not exist");
  }
  // Input that cannot work is refused before anything is created or written.
  const size_t num_image_files = ListImageFiles(image_dir).size();
  if (num_image_files == 0) {
    throw InputError(image_dir.string() + ": no images found (PNG, JPEG, TIFF or BMP by content)");
  }
  if (num_image_files == 1) {
    throw InputError(image_dir.string() + ": only one image; reconstruction needs at least two");
  }
  // 0. Cameras: the intrinsics given, read and checked before anything is written.
  const CameraSetup cameras = LoadCameraSetup(options.extraction.camera);
  const bool coordinator = sharing == nullptr || sharing->IsCoordinator();
  const std::filesystem::path database_path =
      options.database_path.empty() ? output_dir / "database.db" : options.database_path;
  // One run at a time per output folder and per database; a second stops here, before it
  // has written anything. Of a distributed run, the coordinator holds the locks and creates
  // the database before the other ranks open it.
  std::optional<RunLock> output_lock, database_lock;
  std::optional<Database> coordinator_database;
  if (coordinator) {
    CreateDirectoryOrThrow(output_dir);
    output_lock.emplace(OutputLockPath(output_dir), output_dir.string());
    coordinator_database.emplace(database_path);
    database_lock.emplace(DatabaseLockPath(database_path), database_path.string());
  }
  if (sharing != nullptr) sharing->Barrier();
  Database& database =
      coordinator ? *coordinator_database : coordinator_database.emplace(database_path);
  ReconstructionPipelineResult result;
  Timer timer;

  // 1. Features.
  result.extraction = sharing != nullptr
                          ? sharing->Extract(options.extraction, cameras, image_dir, &database)
                          : RunExtractionStage(options.extraction, cameras, image_dir, &database);
  result.timings.emplace_back("features", timer.ElapsedSeconds());
  PARALLAX_LOG(Info) << "features: " << result.extraction.num_extracted << " images extracted, "
                     << result.extraction.num_skipped << " already stored, "
                     << result.extraction.failed.size() << " unreadable, "
                     << result.extraction.mean_num_keypoints << " keypoints per image ("
                     << result.timings.back().second << " s)";
  if (database.NumImages() < 2) {
    throw InputError(image_dir.string() + ": fewer than two readable images");
  }

  // 2 + 3. Matching and geometric verification.
  timer.Restart();
  result.matching = RunMatchingStage(options.matching, &database,
                                     sharing != nullptr ? sharing->Pairs() : nullptr);
  result.timings.emplace_back("matching", timer.ElapsedSeconds());
  PARALLAX_LOG(Info) << "matching: " << result.matching.num_matched << " pairs matched, "
                     << result.matching.num_skipped << " already stored, "
                     << result.matching.num_verified << " verified ("
                     << result.timings.back().second << " s)";

  // 4 + 5. Mapping and outputs.
  timer.Restart();
  MappingStageOptions mapping = options.mapping;
  const std::filesystem::path earlier_model = output_dir / "sparse" / "0";
  if (coordinator && options.extend_model_with_new_photos && mapping.input_model.empty() &&
      mapping.mapper_type == MapperType::kIncremental && mapping.cluster_file.empty() &&
      result.extraction.num_extracted > 0 && HasColmapModel(earlier_model)) {
    mapping.input_model = earlier_model;
    PARALLAX_LOG(Info) << "mapping: " << result.extraction.num_extracted
                       << " new photos are registered into the earlier run's model ("
                       << earlier_model.string() << "); --remap maps all from scratch";
  }
  result.mapping = sharing != nullptr ? sharing->Map(mapping, database, image_dir, output_dir)
                                      : RunMappingStage(mapping, database, image_dir, output_dir);
  result.timings.emplace_back("mapping", timer.ElapsedSeconds());
  if (!coordinator) return result;
  for (const std::string& line : UnregisteredImageLines(result.mapping)) {
    PARALLAX_LOG(Warning) << line;
  }
  if (!result.Success()) return result;
  result.summary = BuildRunSummary(result.mapping, result.timings);
  result.summary["features"] = {{"images_extracted", result.extraction.num_extracted},
                                {"images_skipped_already_stored", result.extraction.num_skipped},
                                {"unreadable", result.extraction.failed.size()},
                                {"mean_keypoints", result.extraction.mean_num_keypoints}};
  result.summary["matching"] = MatchingSummary(result.matching);
  WriteRunSummary(result.summary, output_dir / "summary.json");

  // 6. Evaluation and report.
  const Reconstruction& model = result.mapping.models.front();
  if (!options.ground_truth_path.empty()) {
    result.evaluation =
        EvaluateReconstruction(model, ReadGroundTruth(options.ground_truth_path), {});
  }
  if (options.write_report) {
    timer.Restart();
    HtmlReportInputs inputs;
    inputs.title = options.report_title;
    inputs.reconstruction = &model;
    inputs.database = &database;
    inputs.image_dir = image_dir;
    inputs.summary = result.summary;
    inputs.evaluation = result.evaluation;
    result.report_path = output_dir / "report.html";
    WriteHtmlReport(inputs, result.report_path);
    PARALLAX_LOG(Info) << "report: " << result.report_path.string() << " ("
                       << timer.ElapsedSeconds() << " s)";
  }
  return result;
}

}  // namespace parallax
