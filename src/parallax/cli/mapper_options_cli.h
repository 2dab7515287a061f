#pragma once

#include <CLI/CLI.hpp>

#include "parallax/pipeline/mapping_stage.h"

namespace parallax::cli {

// Mapper flags shared by `parallax mapper` and `parallax reconstruct`.
void AddMapperOptions(CLI::App& app, MappingStageOptions* options);

// Prints the end-of-run summary of the mapping stage to stdout.
void PrintMappingResult(const MappingStageResult& result, const std::filesystem::path& output_dir);

}  // namespace parallax::cli
