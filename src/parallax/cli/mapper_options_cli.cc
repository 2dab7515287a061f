#include "parallax/cli/mapper_options_cli.h"

#include <iostream>
#include <string>

#include "parallax/pipeline/run_summary.h"

namespace parallax::cli {

void AddMapperOptions(CLI::App& app, MappingStageOptions* options) {
  IncrementalMapperOptions& mapper = options->mapper;
  app.add_option("--input-model", options->input_model,
                 "Extend this model (COLMAP format, e.g. OUT/sparse/0): its images keep their "
                 "poses and the database's other images are registered into it (COLMAP's "
                 "mapper --input_path)");
  app.add_flag("--fixed-poses", options->fixed_poses,
               "With --input-model: register nothing; triangulate the database's tracks into "
               "its poses, which stay as given (COLMAP's point_triangulator)")
      ->needs("--input-model");
  app.add_option("--init-min-inliers", mapper.init_min_num_inliers,
                 "Points the initial pair must triangulate")
      ->capture_default_str();
  app.add_option("--init-min-tri-angle", mapper.init_min_triangulation_angle_deg,
                 "Median triangulation angle of the initial pair, degrees")
      ->capture_default_str();
  app.add_option("--init-min-inliers-floor", mapper.init_min_num_inliers_floor,
                 "When no pair qualifies, the two thresholds above are halved in turns, the "
                 "inliers down to this")
      ->capture_default_str();
  app.add_option("--init-min-tri-angle-floor", mapper.init_min_triangulation_angle_floor_deg,
                 "... and the angle down to this, degrees")
      ->capture_default_str();
  app.add_option("--abs-pose-min-inliers", mapper.absolute_pose_min_num_inliers,
                 "PnP inliers an image needs to be registered")
      ->capture_default_str();
  app.add_option("--abs-pose-relaxed-min-inliers", mapper.relaxed_absolute_pose_min_num_inliers,
                 "... in the last pass, when nothing more registers at the usual bars")
      ->capture_default_str();
  app.add_option("--abs-pose-relaxed-min-inlier-ratio",
                 mapper.relaxed_absolute_pose_min_inlier_ratio,
                 "Share of the 2D-3D correspondences that must be PnP inliers in the last pass")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--abs-pose-max-error", mapper.absolute_pose.ransac.max_error,
                 "PnP RANSAC threshold, pixels")
      ->capture_default_str();
  app.add_option("--filter-max-error", mapper.filter.max_reprojection_error_px,
                 "Observations reprojecting further are removed, pixels")
      ->capture_default_str();
  app.add_option("--min-tri-angle", mapper.triangulation.min_angle_deg,
                 "Smallest triangulation angle of a point, degrees")
      ->capture_default_str();
  app.add_option("--tri-max-error", mapper.triangulation.max_reprojection_error_px,
                 "Observations further off do not join a point when it is made, continued, "
                 "completed or merged, pixels")
      ->capture_default_str();
  app.add_option("--tri-ignore-two-view-tracks", mapper.triangulation.ignore_two_view_tracks,
                 "Give no point to features that only two images saw (as COLMAP does)")
      ->capture_default_str();
  app.add_option("--tri-complete-hops", mapper.triangulation.complete_max_transitivity,
                 "Correspondence hops a point grows along when completed (0: no completion)")
      ->capture_default_str();
  app.add_option("--tri-merge", mapper.triangulation.merge_points,
                 "Merge points that correspondences link when one point fits them all")
      ->capture_default_str();
  app.add_option("--tri-retriangulate-ratio", mapper.triangulation.retriangulate_min_ratio,
                 "Image pairs with a smaller share of their matches in points are "
                 "re-triangulated with relaxed thresholds (0: never)")
      ->capture_default_str();
  app.add_option("--ba-global-images-ratio", mapper.global_ba_images_ratio,
                 "Global bundle adjustment when the model has grown by this factor in images "
                 "(COLMAP's Mapper.ba_global_images_ratio)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--ba-global-points-ratio", mapper.global_ba_points_ratio,
                 "... or in points (COLMAP's Mapper.ba_global_points_ratio)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_flag("!--no-multiple-models", mapper.multiple_models,
               "Stop after the first model instead of starting new ones");
  app.add_flag("!--no-join-models", mapper.join_models,
               "Keep the models apart instead of joining those that share tracks");
  app.add_flag_function(
      "--no-refine-intrinsics",
      [&mapper](int64_t) {
        mapper.global_ba.refine_focal_length = false;
        mapper.final_ba.refine_focal_length = false;
      },
      "Keep focal lengths fixed even for cameras without a prior");
  app.add_option_function<int>(
         "--ba-threads",
         [&mapper](int num_threads) {
           for (BundleAdjustmentOptions* ba : mapper.BundleAdjustments())
             ba->num_threads = num_threads;
         },
         "Threads for bundle adjustment (-1: all; any fixed count gives bit-identical runs, "
         "except with --ba-solver ceres above 150 images, where Ceres' threaded Schur "
         "elimination sums in arrival order)")
      ->default_str("-1");
  app.add_option_function<std::string>(
         "--ba-solver",
         [&mapper](const std::string& name) {
           for (BundleAdjustmentOptions* ba : mapper.BundleAdjustments()) {
             ba->solver = BundleAdjustmentSolverFromName(name).value();
           }
         },
         "auto (Parallax's Schur LM: dense up to 250 images, block-sparse with conjugate "
         "gradients above), dense-schur, sparse-schur, ceres or ceres-iterative")
      ->check(CLI::IsMember({"auto", "dense-schur", "sparse-schur", "ceres", "ceres-iterative"}))
      ->default_str("auto");
  app.add_option_function<std::string>(
         "--mapper",
         [options](const std::string& name) {
           options->mapper_type =
               name == "hierarchical" ? MapperType::kHierarchical : MapperType::kIncremental;
         },
         "incremental, or hierarchical for large scenes: overlapping clusters of the view "
         "graph mapped apart (written to OUT/clusters/), merged, then refined as one")
      ->check(CLI::IsMember({"incremental", "hierarchical"}))
      ->default_str("incremental");
  app.add_option("--cluster-max-images", options->hierarchical.partition.max_cluster_images,
                 "Hierarchical mapper: images per cluster before the overlap")
      ->capture_default_str();
  app.add_option("--cluster-overlap", options->hierarchical.partition.overlap_images,
                 "Hierarchical mapper: images a cluster borrows from each neighbouring cluster")
      ->capture_default_str();
  app.add_option_function<std::string>(
         "--ba-loss",
         [&mapper](const std::string& name) {
           mapper.final_ba.loss_function = LossFunctionTypeFromName(name).value();
         },
         "Loss of the final bundle adjustment: cauchy, huber, soft-l1 or squared (local and "
         "intermediate adjustments use squared)")
      ->check(CLI::IsMember({"cauchy", "huber", "soft-l1", "squared"}))
      ->default_str("cauchy");
  app.add_option_function<double>(
         "--ba-loss-scale",
         [&mapper](double scale_px) {
           for (BundleAdjustmentOptions* ba : mapper.BundleAdjustments())
             ba->loss_scale_px = scale_px;
         },
         "Scale of the robust loss, pixels of reprojection error")
      ->default_str("1")
      ->check(CLI::PositiveNumber);
  app.add_flag("!--no-text", options->write_text, "Do not write the .txt model files");
  app.add_flag("!--no-binary", options->write_binary, "Do not write the .bin model files");
}

void PrintMappingResult(const MappingStageResult& result, const std::filesystem::path& output_dir) {
  for (const std::string& line : UnregisteredImageLines(result)) std::cout << line << "\n";
  if (result.models.empty()) return;
  if (result.num_input_model_images > 0) {
    std::cout << "extended the input model: " << result.num_input_model_images
              << " images kept their poses";
    if (!result.input_model_images_missing.empty()) {
      std::cout << ", " << result.input_model_images_missing.size()
                << " of its images are gone and were left out";
    }
    std::cout << "\n";
  }
  for (size_t index = 0; index < result.models.size(); ++index) {
    const Reconstruction& model = result.models[index];
    Reconstruction copy = model;
    std::cout << "model " << index << ": " << model.NumRegImages() << "/"
              << result.image_names.size() << " images registered, " << model.NumPoints3D()
              << " points, mean track length " << model.ComputeMeanTrackLength()
              << ", mean reprojection error " << copy.UpdatePointErrors() << " px -> "
              << (output_dir / "sparse" / std::to_string(index)).string() << "\n";
  }
}

}  // namespace parallax::cli
