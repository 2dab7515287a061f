#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "parallax/pipeline/feature_extraction.h"
#include "parallax/pipeline/feature_matching.h"

namespace parallax::cli {

// Flags of the feature-extraction stage, shared by `features` and `reconstruct`. Call
// Apply() after parsing to convert the textual flags.
class ExtractionFlags {
 public:
  void Add(CLI::App& app, FeatureExtractionOptions* options);
  void Apply(FeatureExtractionOptions* options) const;

 private:
  std::string camera_params_;
  bool no_root_sift_ = false;
};

// Flags of the matching and verification stages, shared by `match` and `reconstruct`.
class MatchingFlags {
 public:
  void Add(CLI::App& app, FeatureMatchingPipelineOptions* options);
  void Apply(FeatureMatchingPipelineOptions* options) const;

 private:
  std::string pair_mode_ = "auto";
  bool no_cross_check_ = false;
};

}  // namespace parallax::cli
