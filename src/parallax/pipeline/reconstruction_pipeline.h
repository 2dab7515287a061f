#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "parallax/pipeline/extraction_stage.h"
#include "parallax/pipeline/mapping_stage.h"
#include "parallax/pipeline/matching_stage.h"
#include "parallax/pipeline/run_summary.h"
#include "parallax/report/evaluation.h"

namespace parallax {

struct ReconstructionPipelineOptions {
  ExtractionStageOptions extraction;
  MatchingStageOptions matching;
  MappingStageOptions mapping;
  // Feature/match database; empty: OUT/database.db. Kept so that a rerun resumes.
  std::filesystem::path database_path;
  // Ground truth (Middlebury *_par.txt or Strecha gt/) to evaluate the first model against;
  // empty: none.
  std::filesystem::path ground_truth_path;
  // When a rerun finds photos that the earlier run's model (OUT/sparse/0) has not seen, they
  // are registered into that model (mapping.input_model) instead of mapping everything from
  // scratch. Off (--remap): from scratch.
  bool extend_model_with_new_photos = true;
  // OUT/report.html, with the evaluation when there is one.
  bool write_report = false;
  std::string report_title = "Parallax reconstruction report";
  void Check() const;
};

struct ReconstructionPipelineResult {
  ExtractionStageResult extraction;
  MatchingStageResult matching;
  MappingStageResult mapping;
  StageTimings timings;
  nlohmann::json summary;
  std::optional<EvaluationMetrics> evaluation;  // With a ground truth.
  std::filesystem::path report_path;            // Empty when no report was written.
  bool Success() const { return !mapping.models.empty(); }
};

// How the ranks of a distributed run share the stages (distributed/, which implements this
// over MPI). Every rank runs the pipeline with it; the coordinator (rank 0) alone takes the
// locks, writes the database and the outputs, and returns the result; the others return an
// empty one after mapping.
class StageSharing {
 public:
  virtual ~StageSharing() = default;
  virtual bool IsCoordinator() const = 0;
  // Returns once every rank has called it.
  virtual void Barrier() = 0;
  // Stage 1: each rank extracts its share; the coordinator stores them all in `database`.
  virtual ExtractionStageResult Extract(const ExtractionStageOptions& options,
                                        const CameraSetup& cameras,
                                        const std::filesystem::path& image_dir,
                                        Database* database) = 0;
  // Stages 2 and 3 (RunMatchingStage's sharing).
  virtual PairSharing* Pairs() = 0;
  // Stage 4: on the coordinator, the models and outputs of RunMappingStage.
  virtual MappingStageResult Map(const MappingStageOptions& options, const Database& database,
                                 const std::filesystem::path& image_dir,
                                 const std::filesystem::path& output_dir) = 0;
};

// The run-wide --seed: the seed of each randomised stage (matching's and mapping's; each
// derives the seeds of its steps from its own).
void SetSeed(uint64_t seed, ReconstructionPipelineOptions* options);

// The run-wide --seed and --threads of `parallax reconstruct`: the seed of verification and
// registration, the worker threads of every stage, bundle adjustment's too unless
// `keep_ba_threads` (--ba-threads was given).
void SetSeedAndThreads(uint64_t seed, int num_threads, bool keep_ba_threads,
                       ReconstructionPipelineOptions* options);

// The paper's pipeline end to end, each stage one call, timed and logged:
//   1. SIFT features of every image            (skips images already in the database)
//   2. matching of the selected pairs + 3. geometric verification (skips verified pairs)
//   4. incremental mapping with bundle adjustment
//   5. outputs: OUT/sparse/<k>/, OUT/points.ply, OUT/summary.json (atomic writes; nothing
//      but the database is written when no model could be started)
//   6. evaluation against the ground truth and OUT/report.html, when asked for.
// With `sharing`, this is one rank's part of a distributed run (see StageSharing).
ReconstructionPipelineResult RunReconstructionPipeline(const ReconstructionPipelineOptions& options,
                                                       const std::filesystem::path& image_dir,
                                                       const std::filesystem::path& output_dir,
                                                       StageSharing* sharing = nullptr);

}  // namespace parallax
