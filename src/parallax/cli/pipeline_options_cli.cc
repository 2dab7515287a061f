#include "parallax/cli/pipeline_options_cli.h"

#include <cstdlib>
#include <string>

#include "parallax/cli/mapper_options_cli.h"
#include "parallax/pipeline/camera_setup.h"

namespace parallax::cli {

void AddExtractionOptions(CLI::App& app, ExtractionStageOptions* options) {
  std::string model_names;
  for (const CameraModelId id : kCameraModelIds) {
    model_names += (model_names.empty() ? "" : ", ") + CameraModelName(id);
  }
  app.add_option("--camera-model", options->camera.camera_model,
                 "COLMAP's camera model: " + model_names +
                     " (default: SIMPLE_RADIAL, or PINHOLE with known intrinsics)");
  auto* params_option = app.add_option_function<std::string>(
      "--camera-params",
      [options](const std::string& text) {
        options->camera.camera_params = ParseCameraParams(text);
      },
      "Intrinsics in the model's order, e.g. fx,fy,cx,cy");
  auto* intrinsics_option = app.add_option("--intrinsics", options->camera.intrinsics_path,
                                           "Text file with the 3x3 calibration matrix K")
                                ->excludes(params_option);
  app.add_option("--camera", options->camera.camera_json_path,
                 "camera.json from `parallax calibrate`: OPENCV intrinsics with distortion")
      ->excludes(params_option)
      ->excludes(intrinsics_option);
  app.add_flag("--refine-camera", options->camera.refine_known_intrinsics,
               "Use --camera/--intrinsics/--camera-params as initial values that bundle "
               "adjustment refines (default: held fixed)");
  app.add_flag("!--no-exif", options->camera.use_exif,
               "Ignore EXIF focal lengths (unknown intrinsics start from 1.2 x the longer side)");
  app.add_option("--sensor-width", options->camera.sensor_width_mm,
                 "Sensor width in mm, to turn an EXIF FocalLength into pixels when the image has "
                 "no FocalPlaneXResolution (used before FocalLengthIn35mmFilm)")
      ->check(CLI::PositiveNumber);
  auto* single_flag =
      app.add_flag("--single-camera", options->camera.single_camera, "One camera for all images");
  app.add_flag("--camera-per-image", options->camera.camera_per_image, "One camera per image")
      ->excludes(single_flag);
  app.add_option("--max-features", options->sift.max_num_features, "Keypoints kept per image")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-image-size", options->sift.max_image_size,
                 "Longest side in pixels before detection (larger images are downscaled)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-upsampled-size", options->sift.max_upsampled_image_size,
                 "Longest side up to which SIFT's first octave doubles the image; larger images "
                 "start at their own resolution (0: always double)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-image-pixels", options->reader.max_image_pixels,
                 "Refuse images with more pixels than this, before decoding")
      ->capture_default_str();
  app.add_option("--sift-contrast", options->sift.contrast_threshold,
                 "SIFT contrast threshold, OpenCV convention (0.02, COLMAP's default peak "
                 "threshold: 56 % more keypoints than the paper's 0.04 on templeRing)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--sift-edge", options->sift.edge_threshold, "SIFT edge threshold")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_flag("!--no-root-sift", options->sift.root_sift,
               "Plain L2-normalised SIFT instead of RootSIFT");
  SiftExtractionOptions& sift = options->sift;
  app.add_option_function<std::string>(
         "--sift",
         [&sift](const std::string& name) {
           sift.implementation = *SiftImplementationFromName(name);
         },
         "SIFT implementation: native (Parallax's own: float descriptors before RootSIFT, "
         "exact positions) or opencv (OpenCV's cv::SIFT)")
      ->default_str(SiftImplementationName(sift.implementation))
      ->check(CLI::IsMember({"native", "opencv"}));
  app.add_option("--sift-max-orientations", sift.max_num_orientations,
                 "Native SIFT: keypoints per extremum with distinct dominant orientations")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

void AddMatchingOptions(CLI::App& app, MatchingStageOptions* options) {
  PairSelectionOptions& pairs = options->pairs;
  app.add_option_function<std::string>(
         "--pairs", [&pairs](const std::string& name) { pairs.mode = *PairModeFromName(name); },
         "Which pairs to match: auto (exhaustive up to --auto-exhaustive-max-images, "
         "retrieval above, plus spatial when images have GPS), exhaustive, sequential "
         "(name order), retrieval (vocabulary tree), spatial (EXIF GPS neighbours) or list "
         "(the pairs --pair-list names)")
      ->default_str("auto")
      ->check(CLI::IsMember({"auto", "exhaustive", "sequential", "retrieval", "spatial", "list"}));
  app.add_option("--pair-list", pairs.pair_list_path,
                 "List mode: a text file of pairs, two image names per line (COLMAP's "
                 "matches_importer --match_type pairs)")
      ->check(CLI::ExistingFile);
  app.add_option("--auto-exhaustive-max-images", pairs.auto_exhaustive_max_images,
                 "Auto mode: match every pair up to this many images")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000000));
  app.add_option("--overlap", pairs.sequential_overlap,
                 "Sequential mode: neighbours matched per image")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option(
         "--vocab-tree", pairs.retrieval.vocab_tree_path,
         "Retrieval: a vocabulary tree saved by an earlier run (default: the one beside the "
         "database, or one trained on this collection and saved there)")
      ->check(CLI::ExistingFile);
  app.add_option("--retrieval-neighbors", pairs.retrieval.num_neighbors,
                 "Retrieval: most similar images matched per image")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--retrieval-neighbors-with-gps", pairs.retrieval.num_neighbors_with_gps,
                 "Retrieval: most similar images matched per image where GPS neighbours are "
                 "matched too (auto mode, images with positions)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--retrieval-loop-neighbors", pairs.retrieval.num_loop_neighbors,
                 "Retrieval: after verification, images sharing the most verified neighbours "
                 "matched per image, to close loops retrieval missed (0: none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--retrieval-loop-rounds", pairs.retrieval.num_loop_rounds,
                 "Retrieval: rounds of loop-closing pairs, each from the pairs verified so far")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--vocab-tree-depth", pairs.retrieval.tree.depth,
                 "Retrieval: levels of a newly trained tree (up to branching^depth words)")
      ->capture_default_str()
      ->check(CLI::Range(1, 8));
  app.add_option("--vocab-tree-branching", pairs.retrieval.tree.branching,
                 "Retrieval: children per node of a newly trained tree")
      ->capture_default_str()
      ->check(CLI::Range(2, 256));
  app.add_option("--spatial-neighbors", pairs.spatial.num_neighbors,
                 "Spatial: nearest images by GPS matched per image")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--spatial-max-distance", pairs.spatial.max_distance,
                 "Spatial: farthest GPS distance of a pair, metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_flag("--preemptive,!--no-preemptive", options->preemptive.enabled,
               "Match each pair's largest features first and skip pairs that find too few (Wu "
               "2013; off by default, see docs/pair-selection.md)");
  app.add_option("--preemptive-features", options->preemptive.num_features,
                 "Preemptive test: largest-scale features matched per image")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--preemptive-ratio", options->preemptive.max_ratio,
                 "Preemptive test: Lowe's ratio of its matches (0: --ratio)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--preemptive-min-matches", options->preemptive.min_matches,
                 "Preemptive test: fewer matches skip the pair")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option_function<std::string>(
         "--approximate-matching",
         [options](const std::string& name) {
           options->approximate.mode = *ApproximateMatchingModeFromName(name);
         },
         "Compare each descriptor only with the other image's descriptors in its cells of a "
         "coarse k-means partition: auto (on where the pairs come from retrieval or GPS, or "
         "where images have 512 descriptors or more on average, as COLMAP 4's CPU matcher), "
         "on or off (see docs/pair-selection.md)")
      ->default_str("auto")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  app.add_option("--matching-cells", options->approximate.cells.num_cells,
                 "Approximate matching: cells of the partition")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--matching-cell-assignments", options->approximate.cells.num_assignments,
                 "Approximate matching: nearest cells each searched descriptor is filed under")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--ratio", options->matching.max_ratio, "Lowe's ratio test threshold")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("!--no-cross-check", options->matching.cross_check,
               "Keep matches that are not mutual");
  app.add_option("--max-error", options->geometry.ransac.max_error,
                 "Geometric verification RANSAC threshold, pixels")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--confidence", options->geometry.ransac.confidence,
                 "Geometric verification RANSAC confidence (COLMAP's SiftMatching.confidence)")
      ->capture_default_str()
      ->check([](const std::string& text) -> std::string {
        const double value = std::atof(text.c_str());
        return value >= 0.5 && value < 1.0 ? "" : "must be at least 0.5 and below 1";
      });
  app.add_flag(
      "--uncalibrated-fallback", options->geometry.uncalibrated_fallback,
      "With known intrinsics, also search for an F where E explains too few matches (COLMAP's "
      "rule; for COLMAP databases whose prior focal lengths come from EXIF)");
  app.add_option("--max-num-trials", options->geometry.ransac.max_num_trials,
                 "Geometric verification RANSAC trials at most, per model (E, F, H)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option_function<std::string>(
         "--ransac-sampler",
         [options](const std::string& name) {
           const bool progressive = name == "progressive";
           options->geometry.ransac.sampler =
               progressive ? RansacSampler::kProgressive : RansacSampler::kUniform;
           options->matching.order_by_ratio = progressive;
         },
         "Geometric verification's RANSAC samples: uniform, or progressive (PROSAC: each pair's "
         "matches ordered by Lowe's ratio and sampled from the most distinctive on)")
      ->default_str("uniform")
      ->check(CLI::IsMember({"uniform", "progressive"}));
  app.add_option("--match-batch-size", options->batch_size,
                 "Pairs stored per transaction: a killed run loses at most one batch of work")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

void AddReconstructionOptions(CLI::App& app, ReconstructionPipelineOptions* options) {
  AddExtractionOptions(app, &options->extraction);
  AddMatchingOptions(app, &options->matching);
  AddMapperOptions(app, &options->mapping);
}

}  // namespace parallax::cli
