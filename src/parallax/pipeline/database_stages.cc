#include "parallax/pipeline/database_stages.h"

#include "parallax/pipeline/run_summary.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/run_lock.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

void RequireDatabase(const std::filesystem::path& database_path, const char* hint) {
  if (!std::filesystem::exists(database_path)) {
    throw MissingFileError(database_path.string() + ": database does not exist" + hint);
  }
}

}  // namespace

ExtractionStageResult ExtractFeaturesIntoDatabase(const ExtractionStageOptions& options,
                                                  const std::filesystem::path& image_dir,
                                                  const std::filesystem::path& database_path) {
  Database database(database_path);
  const RunLock lock(DatabaseLockPath(database_path), database_path.string());
  ExtractionStageResult result = RunExtractionStage(options, image_dir, &database);
  if (result.num_images_found == 0) throw InputError(image_dir.string() + ": no images found");
  return result;
}

MatchingStageResult MatchDatabase(const MatchingStageOptions& options,
                                  const std::filesystem::path& database_path) {
  RequireDatabase(database_path, " (extract features first)");
  Database database(database_path);
  const RunLock lock(DatabaseLockPath(database_path), database_path.string());
  return RunMatchingStage(options, &database);
}

MappingStageResult MapDatabase(const MappingStageOptions& options,
                               const std::filesystem::path& database_path,
                               const std::filesystem::path& image_dir,
                               const std::filesystem::path& output_dir) {
  RequireDatabase(database_path, "");
  CreateDirectoryOrThrow(output_dir);
  const RunLock output_lock(OutputLockPath(output_dir), output_dir.string());
  Database database(database_path);
  const RunLock database_lock(DatabaseLockPath(database_path), database_path.string());
  const Timer timer;
  MappingStageResult result = RunMappingStage(options, database, image_dir, output_dir);
  if (!result.models.empty()) {
    WriteRunSummary(BuildRunSummary(result, {{"mapping", timer.ElapsedSeconds()}}),
                    output_dir / "summary.json");
  }
  return result;
}

}  // namespace parallax
