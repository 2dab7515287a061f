#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "parallax/pipeline/extraction_stage.h"
#include "parallax/pipeline/matching_stage.h"
#include "parallax/pipeline/reconstruction_pipeline.h"

namespace parallax::cli {

// Command-line flags bound straight to the options they set (conversions in the flag's own
// callback), shared by `features`/`match` and `reconstruct`, as AddMapperOptions is for the
// mapper's.
void AddExtractionOptions(CLI::App& app, ExtractionStageOptions* options);
void AddMatchingOptions(CLI::App& app, MatchingStageOptions* options);
// The three stages' flags together, as `reconstruct` (and Python's reconstruct) takes them.
void AddReconstructionOptions(CLI::App& app, ReconstructionPipelineOptions* options);

}  // namespace parallax::cli
