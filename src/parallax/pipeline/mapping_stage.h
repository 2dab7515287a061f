#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "parallax/scene/database.h"
#include "parallax/sfm/hierarchical_mapper.h"
#include "parallax/sfm/incremental_mapper.h"

namespace parallax {

enum class MapperType {
  kIncremental,   // One incremental mapper over all images.
  kHierarchical,  // Overlapping clusters mapped apart, merged, refined (large scenes).
};

struct MappingStageOptions {
  MapperInputOptions input;
  IncrementalMapperOptions mapper;
  MapperType mapper_type = MapperType::kIncremental;
  // Why mapper_type is what it is when the run chose it rather than the user (a distributed
  // run maps by clusters); logged and written to summary.json as mapper.type_reason.
  std::string mapper_type_reason;
  HierarchicalMapperOptions hierarchical;  // With kHierarchical.
  // When set, only the images and pairs of this cluster file are mapped (incrementally): the
  // unit of work of a partitioned run.
  std::filesystem::path cluster_file;
  // A finished model (COLMAP format) to extend, as COLMAP's `mapper --input_path`: its images
  // keep their poses (matched to the database by name) and the database's other images are
  // registered into it; its points are triangulated anew from the database. Empty: map from
  // scratch.
  std::filesystem::path input_model;
  // With input_model: register nothing, only triangulate the database's tracks into its fixed
  // poses (COLMAP's point_triangulator; TriangulateIntoPoses).
  bool fixed_poses = false;
  bool write_text = true;    // cameras.txt, images.txt, points3D.txt
  bool write_binary = true;  // the .bin twins
  void Check() const;
};

// Result of the mapping stage, enough for summary.json and the report.
struct MappingStageResult {
  std::vector<Reconstruction> models;  // Largest first; empty when no model could start.
  MapperSummary summary;
  std::optional<HierarchicalMapperSummary> hierarchical;  // With MapperType::kHierarchical.
  std::string mapper_type_reason;                         // options.mapper_type_reason.
  std::map<image_t, std::string> image_names;
  std::map<image_t, size_t> num_keypoints;
  double load_seconds = 0;
  double write_seconds = 0;
  // With options.input_model: its registered images that seeded the mapper, and those of its
  // images the database no longer holds (left out).
  size_t num_input_model_images = 0;
  std::vector<std::string> input_model_images_missing;
};

// Loads the database, runs the mapper, colours the points from the images in `image_dir`
// (when readable) and writes OUT/sparse/<k>/ and OUT/points.ply atomically; the hierarchical
// mapper also writes its clusters as OUT/clusters/cluster-<k>.txt. Nothing is written when
// no model could be started.
MappingStageResult RunMappingStage(const MappingStageOptions& options, const Database& database,
                                   const std::filesystem::path& image_dir,
                                   const std::filesystem::path& output_dir);

// The stage's last step: colours the models' points (ColorizePoints) and writes them
// (nothing when there is no model), timed in result->write_seconds.
void ColorizeAndWriteModels(const MappingStageOptions& options, const Database* database,
                            const std::filesystem::path& image_dir,
                            const std::filesystem::path& output_dir, MappingStageResult* result);
// Names and keypoint counts of the input's images, and the log line that describes it.
void DescribeMapperInput(const MapperInput& input, MappingStageResult* result);

// Writes each cluster (ids of `input`) as DIR/cluster-<k>.txt, replacing what DIR held.
void WriteClusterFiles(const MapperInput& input, const std::vector<std::vector<image_t>>& clusters,
                       const std::filesystem::path& dir);

// Sets every point's colour to the mean colour of its observations: from the keypoint colours
// `database` (optional) stored at extraction for an image of the same name and as many
// keypoints as the model's image has points, else from the image in `image_dir` (empty: none,
// left black). Images that cannot be read are skipped with a warning.
void ColorizePoints(const std::filesystem::path& image_dir, const Database* database,
                    Reconstruction* reconstruction);

// Writes the models to OUT/sparse/<index>/ and the first one's points to OUT/points.ply,
// replacing the whole sparse/ folder of an earlier run at once (written beside it, then
// renamed) and removing its summary.json, which the caller writes again last.
void WriteModels(const std::vector<Reconstruction>& models, const std::filesystem::path& output_dir,
                 bool write_text, bool write_binary);

}  // namespace parallax
