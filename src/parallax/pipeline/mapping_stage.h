#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "parallax/scene/database.h"
#include "parallax/sfm/incremental_mapper.h"

namespace parallax {

struct MappingStageOptions {
  MapperInputOptions input;
  IncrementalMapperOptions mapper;
  bool write_text = true;    // cameras.txt, images.txt, points3D.txt
  bool write_binary = true;  // the .bin twins
  void Check() const;
};

// Result of the mapping stage, enough for summary.json and the report.
struct MappingStageResult {
  std::vector<Reconstruction> models;  // Largest first; empty when no model could start.
  MapperSummary summary;
  std::map<image_t, std::string> image_names;
  std::map<image_t, size_t> num_keypoints;
  double load_seconds = 0;
  double write_seconds = 0;
};

// Loads the database, runs the incremental mapper, colours the points from the images in
// `image_dir` (when readable) and writes OUT/sparse/<k>/ and OUT/points.ply atomically.
// Nothing is written when no model could be started.
MappingStageResult RunMappingStage(const MappingStageOptions& options, const Database& database,
                                   const std::filesystem::path& image_dir,
                                   const std::filesystem::path& output_dir);

// Sets every point's colour to the mean colour of its observations in the images.
// Images that cannot be read are skipped with a warning.
void ColorizePoints(const std::filesystem::path& image_dir, Reconstruction* reconstruction);

// Writes the models to OUT/sparse/<index>/ and the first one's points to OUT/points.ply,
// replacing the whole sparse/ folder of an earlier run at once (written beside it, then
// renamed) and removing its summary.json, which the caller writes again last.
void WriteModels(const std::vector<Reconstruction>& models, const std::filesystem::path& output_dir,
                 bool write_text, bool write_binary);

}  // namespace parallax
