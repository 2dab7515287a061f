#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "parallax/pipeline/extraction_stage.h"
#include "parallax/pipeline/matching_stage.h"

namespace parallax::cli {

// Command-line flags bound straight to the options they set (conversions in the flag's own
// callback), shared by `features`/`match` and `reconstruct`, as AddMapperOptions is for the
// mapper's.
void AddExtractionOptions(CLI::App& app, ExtractionStageOptions* options);
void AddMatchingOptions(CLI::App& app, MatchingStageOptions* options);

}  // namespace parallax::cli
