#pragma once

#include <filesystem>

#include "parallax/pipeline/extraction_stage.h"
#include "parallax/pipeline/mapping_stage.h"
#include "parallax/pipeline/matching_stage.h"

namespace parallax {

// The stages run one at a time on a database file, as `parallax features`, `match` and
// `mapper` (and the Python module's extract_features, match and map) run them: each opens the
// database under its run lock (util/run_lock.h), so two runs never write one database at once.

// Stage 1 into `database_path` (created when missing). Throws InputError when the folder holds
// no image.
ExtractionStageResult ExtractFeaturesIntoDatabase(const ExtractionStageOptions& options,
                                                  const std::filesystem::path& image_dir,
                                                  const std::filesystem::path& database_path);

// Stages 2 and 3 on an existing database (MissingFileError when there is none).
MatchingStageResult MatchDatabase(const MatchingStageOptions& options,
                                  const std::filesystem::path& database_path);

// Stage 4 on an existing database, into `output_dir` (created; locked while mapping), then
// OUT/summary.json with the mapping time when a model was made.
MappingStageResult MapDatabase(const MappingStageOptions& options,
                               const std::filesystem::path& database_path,
                               const std::filesystem::path& image_dir,
                               const std::filesystem::path& output_dir);

}  // namespace parallax
