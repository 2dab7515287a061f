#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "parallax/pipeline/mapping_stage.h"
#include "parallax/pipeline/matching_stage.h"

namespace parallax {

// Wall time of each stage of a run, in seconds, in the order they ran.
using StageTimings = std::vector<std::pair<std::string, double>>;

// summary.json: images registered / total, points, mean track length, mean reprojection
// error, per-stage wall times, and per image its keypoints, observations, reprojection error
// before and after bundle adjustment, and the reason when it was not registered.
nlohmann::json BuildRunSummary(const MappingStageResult& result, const StageTimings& timings);

// The matching stage: how pairs were chosen and why, pairs considered, matched, stopped by
// the preemptive test, verified, and the time of each part.
nlohmann::json MatchingSummary(const MatchingStageResult& stats);

void WriteRunSummary(const nlohmann::json& summary, const std::filesystem::path& path);

// One line per unregistered image with its reason, for the log.
std::vector<std::string> UnregisteredImageLines(const MappingStageResult& result);

}  // namespace parallax
