#pragma once

#include <filesystem>

#include "parallax/pipeline/feature_extraction.h"
#include "parallax/pipeline/feature_matching.h"
#include "parallax/pipeline/mapping_stage.h"
#include "parallax/pipeline/run_summary.h"

namespace parallax {

struct ReconstructionPipelineOptions {
  FeatureExtractionOptions extraction;
  FeatureMatchingPipelineOptions matching;
  MappingStageOptions mapping;
  // Feature/match database; empty: OUT/database.db. Kept so that a rerun resumes.
  std::filesystem::path database_path;
  void Check() const;
};

struct ReconstructionPipelineResult {
  FeatureExtractionStats extraction;
  FeatureMatchingStats matching;
  MappingStageResult mapping;
  StageTimings timings;
  nlohmann::json summary;
  bool Success() const { return !mapping.models.empty(); }
};

// The paper's pipeline end to end, each stage one call, timed and logged:
//   1. SIFT features of every image            (skips images already in the database)
//   2. matching of the selected pairs + 3. geometric verification (skips verified pairs)
//   4. incremental mapping with bundle adjustment
//   5. outputs: OUT/sparse/<k>/, OUT/points.ply, OUT/summary.json (atomic writes; nothing
//      but the database is written when no model could be started).
ReconstructionPipelineResult RunReconstructionPipeline(const ReconstructionPipelineOptions& options,
                                                       const std::filesystem::path& image_dir,
                                                       const std::filesystem::path& output_dir);

}  // namespace parallax
