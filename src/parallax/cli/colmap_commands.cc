// The `colmap` drop-in's subcommands: each translates COLMAP's options (both generations)
// into the Parallax subcommand that does the same work, and runs it in this process. Outputs
// land where COLMAP puts them.
#include "parallax/cli/colmap_commands.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "parallax/cli/colmap_flags.h"
#include "parallax/cli/commands.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax::cli {

namespace {

using Kind = ColmapOption::Kind;

ColmapOption Value(std::vector<std::string> names, std::string parallax_flag) {
  return {std::move(names), Kind::kValue, std::move(parallax_flag), "", nullptr};
}
ColmapOption FlagIfOn(std::vector<std::string> names, std::string parallax_flag) {
  return {std::move(names), Kind::kFlagIfOn, std::move(parallax_flag), "", nullptr};
}
ColmapOption FlagIfOff(std::vector<std::string> names, std::string parallax_flag) {
  return {std::move(names), Kind::kFlagIfOff, std::move(parallax_flag), "", nullptr};
}
ColmapOption Ignored(std::vector<std::string> names, std::string why) {
  return {std::move(names), Kind::kIgnored, "", std::move(why), nullptr};
}
ColmapOption Custom(std::vector<std::string> names,
                    std::function<void(const std::string&, std::vector<std::string>*)> apply) {
  return {std::move(names), Kind::kCustom, "", "", std::move(apply)};
}
// An option the drop-in itself uses (not passed on): its value is kept in `*kept`.
ColmapOption Kept(std::vector<std::string> names, std::string* kept) {
  return Custom(std::move(names),
                [kept](const std::string& value, std::vector<std::string>*) { *kept = value; });
}

// An option under its 4.x section and its 3.x one (COLMAP 4 moved the options that are not
// SIFT's own from SiftExtraction/SiftMatching to FeatureExtraction/FeatureMatching).
std::vector<std::string> Extraction(const std::string& option) {
  return {"FeatureExtraction." + option, "SiftExtraction." + option};
}
std::vector<std::string> Matching(const std::string& option) {
  return {"FeatureMatching." + option, "SiftMatching." + option};
}

const char* kNoGpu = "has no meaning for Parallax (no GPU is used)";
const char* kNotImplemented = "is a SIFT variant Parallax does not implement";

// The translation's warnings, one line each.
void PrintWarnings(const ColmapTranslation& translation) {
  for (const std::string& warning : translation.warnings) {
    std::cerr << "colmap: warning: " << warning << std::endl;
  }
}

// Runs a Parallax subcommand on translated arguments, after the warnings.
int RunTranslated(int (*run)(int, char**), const std::string& parallax_command,
                  const ColmapTranslation& translation) {
  PrintWarnings(translation);
  std::vector<std::string> args = {parallax_command};
  args.insert(args.end(), translation.parallax_args.begin(), translation.parallax_args.end());
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  return run(static_cast<int>(args.size()), argv.data());
}

// Translates and runs, turning a bad option into COLMAP's kind of failure: one line, exit 1.
int Translate(const std::string& subcommand, int argc, char** argv,
              const std::vector<ColmapOption>& table,
              const std::function<int(const ColmapTranslation&)>& run) {
  try {
    const ColmapTranslation translation =
        TranslateColmapArgs(subcommand, std::vector<std::string>(argv + 1, argv + argc), table);
    if (translation.help) {
      std::cout << "colmap " << subcommand << " (Parallax). Options:\n";
      for (const ColmapOption& option : table) {
        std::cout << "  --" << option.names.front();
        for (size_t i = 1; i < option.names.size(); ++i) std::cout << " | --" << option.names[i];
        if (option.kind == Kind::kIgnored) std::cout << "  (accepted, ignored)";
        std::cout << "\n";
      }
      return 0;
    }
    return run(translation);
  } catch (const InputError& error) {
    std::cerr << "error: " << error.what() << std::endl;
    return 1;
  } catch (const std::filesystem::filesystem_error& error) {
    // Moving the mapper's models into <output_path> (a full disk, a file in the way).
    std::cerr << "error: colmap " << subcommand << ": " << error.what() << std::endl;
    return 1;
  }
}

std::vector<ColmapOption> ExtractionOptions() {
  return {
      Value({"database_path"}, "--database"),
      Value({"image_path"}, "--images"),
      Value({"ImageReader.camera_model"}, "--camera-model"),
      FlagIfOn({"ImageReader.single_camera"}, "--single-camera"),
      FlagIfOn({"ImageReader.single_camera_per_image"}, "--camera-per-image"),
      Custom({"ImageReader.camera_params"},
             [](const std::string& value, std::vector<std::string>* args) {
               if (value.empty()) return;  // COLMAP's "unknown": from EXIF or a guess.
               args->push_back("--camera-params");
               args->push_back(value);
             }),
      Ignored({"ImageReader.default_focal_length_factor"},
              "is not used: Parallax guesses 1.2 x the longer side without EXIF"),
      Ignored({"ImageReader.mask_path"}, "is not supported yet (masks)"),
      Ignored({"ImageReader.existing_camera_id"}, "is not supported"),
      Value(Extraction("num_threads"), "--threads"),
      Ignored(Extraction("use_gpu"), kNoGpu),
      Ignored(Extraction("gpu_index"), kNoGpu),
      Value(Extraction("max_image_size"), "--max-image-size"),
      Value({"SiftExtraction.max_num_features"}, "--max-features"),
      Value({"SiftExtraction.max_num_orientations"}, "--sift-max-orientations"),
      Value({"SiftExtraction.edge_threshold"}, "--sift-edge"),
      // COLMAP's peak threshold is per scale-space level (3 per octave); Parallax's contrast
      // threshold is OpenCV's, per octave (docs/defaults.md, "SIFT contrast 0.02").
      Custom({"SiftExtraction.peak_threshold"},
             [](const std::string& value, std::vector<std::string>* args) {
               args->push_back("--sift-contrast");
               args->push_back(std::to_string(3.0 * std::stod(value)));
             }),
      Ignored({"SiftExtraction.estimate_affine_shape"}, kNotImplemented),
      Ignored({"SiftExtraction.domain_size_pooling"}, kNotImplemented),
      Ignored({"SiftExtraction.upright"}, kNotImplemented),
      Ignored({"SiftExtraction.first_octave", "SiftExtraction.octave_resolution",
               "SiftExtraction.num_octaves"},
              "is fixed in Parallax's SIFT"),
  };
}

// What both matchers take (the pairs they match set apart).
std::vector<ColmapOption> MatchingOptions() {
  return {
      Value({"database_path"}, "--database"),
      Value(Matching("num_threads"), "--threads"),
      Ignored(Matching("use_gpu"), kNoGpu),
      Ignored(Matching("gpu_index"), kNoGpu),
      Value({"SiftMatching.max_ratio", "FeatureMatching.max_ratio"}, "--ratio"),
      FlagIfOff({"SiftMatching.cross_check", "FeatureMatching.cross_check"}, "--no-cross-check"),
      Value({"TwoViewGeometry.max_error", "SiftMatching.max_error"}, "--max-error"),
      Value({"TwoViewGeometry.confidence", "SiftMatching.confidence"}, "--confidence"),
      Value({"TwoViewGeometry.max_num_trials", "SiftMatching.max_num_trials"}, "--max-num-trials"),
      Ignored(Matching("guided_matching"), "is not implemented (matches are verified once)"),
      Ignored(Matching("max_num_matches"), "is not limited in Parallax"),
      Ignored({"TwoViewGeometry.min_num_inliers", "SiftMatching.min_num_inliers"},
              "is the mapper's concern in Parallax (15 inliers)"),
  };
}

}  // namespace

int RunColmapFeatureExtractor(int argc, char** argv) {
  return Translate("feature_extractor", argc, argv, ExtractionOptions(),
                   [](const ColmapTranslation& translation) {
                     return RunTranslated(RunFeatures, "features", translation);
                   });
}

int RunColmapExhaustiveMatcher(int argc, char** argv) {
  std::vector<ColmapOption> table = MatchingOptions();
  table.push_back(Ignored({"ExhaustiveMatching.block_size"}, "is not used: pairs go in batches"));
  return Translate("exhaustive_matcher", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.end(), {"--pairs", "exhaustive"});
    return RunTranslated(RunMatch, "match", translation);
  });
}

int RunColmapSequentialMatcher(int argc, char** argv) {
  std::vector<ColmapOption> table = MatchingOptions();
  table.push_back(Value({"SequentialMatching.overlap"}, "--overlap"));
  table.push_back(Ignored({"SequentialMatching.quadratic_overlap"},
                          "is not implemented (each image is matched with its next neighbours)"));
  table.push_back(Ignored({"SequentialMatching.loop_detection"},
                          "is not implemented with sequential pairs (use vocab_tree_matcher)"));
  table.push_back(
      Ignored({"SequentialMatching.vocab_tree_path"}, "is not used by sequential pairs"));
  return Translate("sequential_matcher", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.end(), {"--pairs", "sequential"});
    return RunTranslated(RunMatch, "match", translation);
  });
}

int RunColmapVocabTreeMatcher(int argc, char** argv) {
  std::vector<ColmapOption> table = MatchingOptions();
  table.push_back(Value({"VocabTreeMatching.num_images"}, "--retrieval-neighbors"));
  table.push_back(Ignored({"VocabTreeMatching.vocab_tree_path"},
                          "is COLMAP's tree format: Parallax trains its own on the database's "
                          "descriptors"));
  table.push_back(
      Ignored({"VocabTreeMatching.num_nearest_neighbors", "VocabTreeMatching.num_checks",
               "VocabTreeMatching.num_images_after_verification",
               "VocabTreeMatching.max_num_features", "VocabTreeMatching.match_list_path"},
              "is not used by Parallax's retrieval"));
  return Translate("vocab_tree_matcher", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.end(), {"--pairs", "retrieval"});
    return RunTranslated(RunMatch, "match", translation);
  });
}

int RunColmapSpatialMatcher(int argc, char** argv) {
  std::vector<ColmapOption> table = MatchingOptions();
  table.push_back(Value({"SpatialMatching.max_num_neighbors"}, "--spatial-neighbors"));
  table.push_back(Value({"SpatialMatching.max_distance"}, "--spatial-max-distance"));
  table.push_back(Ignored({"SpatialMatching.is_gps", "SpatialMatching.ignore_z"},
                          "is decided from the priors Parallax reads (GPS positions are "
                          "compared in local metres)"));
  return Translate("spatial_matcher", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.end(), {"--pairs", "spatial"});
    return RunTranslated(RunMatch, "match", translation);
  });
}

int RunColmapMatchesImporter(int argc, char** argv) {
  std::vector<ColmapOption> table = MatchingOptions();
  table.push_back(Value({"match_list_path"}, "--pair-list"));
  table.push_back(Custom({"match_type"}, [](const std::string& value, std::vector<std::string>*) {
    if (value != "pairs") {
      throw InputError("colmap matches_importer: --match_type " + value +
                       " is not supported yet (pairs: Parallax matches and verifies the listed "
                       "pairs)");
    }
  }));
  table.push_back(Ignored({"FeatureMatching.skip_geometric_verification"},
                          "is not used: every pair is verified"));
  table.push_back(Ignored(
      {"FeatureMatching.rig_verification", "FeatureMatching.skip_image_pairs_in_same_frame"},
      "applies to rigs, which Parallax does not model yet"));
  table.push_back(
      Ignored({"FeatureMatching.type", "SiftMatching.max_distance",
               "SiftMatching.cpu_brute_force_matcher", "SiftMatching.planar_scene",
               "SiftMatching.multiple_models", "SiftMatching.compute_relative_pose",
               "SiftMatching.min_inlier_ratio", "TwoViewGeometry.min_inlier_ratio",
               "TwoViewGeometry.multiple_models", "TwoViewGeometry.compute_relative_pose",
               "TwoViewGeometry.detect_watermark", "TwoViewGeometry.random_seed"},
              "is decided by Parallax's matcher (docs/defaults.md)"));
  return Translate("matches_importer", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.end(), {"--pairs", "list"});
    return RunTranslated(RunMatch, "match", translation);
  });
}

int RunColmapModelAnalyzer(int argc, char** argv) {
  const std::vector<ColmapOption> table = {
      Custom({"path"}, [](const std::string& value,
                          std::vector<std::string>* args) { args->push_back(value); }),
  };
  return Translate("model_analyzer", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.begin(), "analyze");
    return RunTranslated(RunModel, "model", translation);
  });
}

namespace {

// The rest of COLMAP 3.8's and 4.2's Mapper options: accepted so that scripts tuned for
// COLMAP run; Parallax's mapper decides these by its own criteria (docs/defaults.md).
std::vector<std::string> OtherMapperOptions() {
  std::vector<std::string> names;
  for (const char* name : {"abs_pose_min_inlier_ratio",
                           "ba_global_backend",
                           "ba_global_frames_freq",
                           "ba_global_ignore_redundant_points3D",
                           "ba_global_ignore_redundant_points3D_min_coverage_gain",
                           "ba_global_images_freq",
                           "ba_global_max_refinement_change",
                           "ba_global_max_refinements",
                           "ba_global_pba_gpu_index",
                           "ba_global_points_freq",
                           "ba_global_use_pba",
                           "ba_local_backend",
                           "ba_local_max_refinement_change",
                           "ba_local_max_refinements",
                           "ba_local_min_tri_angle",
                           "ba_local_num_images",
                           "ba_min_num_residuals_for_cpu_multi_threading",
                           "ba_min_num_residuals_for_multi_threading",
                           "ba_refine_sensor_from_rig",
                           "constant_camera_list_path",
                           "constant_rig_list_path",
                           "filter_min_tri_angle",
                           "fix_existing_frames",
                           "fix_existing_images",
                           "ignore_watermarks",
                           "image_list_path",
                           "init_image_id1",
                           "init_image_id2",
                           "init_max_error",
                           "init_max_forward_motion",
                           "init_max_reg_trials",
                           "init_num_trials",
                           "local_ba_min_tri_angle",
                           "max_extra_param",
                           "max_focal_length_ratio",
                           "max_model_overlap",
                           "max_num_models",
                           "max_reg_trials",
                           "max_runtime_seconds",
                           "min_focal_length_ratio",
                           "min_model_size",
                           "min_num_matches",
                           "snapshot_frames_freq",
                           "snapshot_images_freq",
                           "snapshot_path",
                           "structure_less_registration_fallback",
                           "structure_less_registration_only",
                           "tri_complete_max_reproj_error",
                           "tri_continue_max_angle_error",
                           "tri_create_max_angle_error",
                           "tri_max_transitivity",
                           "tri_merge_max_reproj_error",
                           "tri_re_max_angle_error",
                           "tri_re_max_trials",
                           "tri_re_min_ratio"}) {
    names.push_back(std::string("Mapper.") + name);
  }
  return names;
}

// COLMAP's mapper options, for mapper and hierarchical_mapper; `output_path` is kept aside:
// both write <output_path>/<k>/ where Parallax writes OUT/sparse/<k>/.
std::vector<ColmapOption> MapperOptions(std::string* output_path) {
  return {
      Value({"database_path"}, "--database"),
      Value({"image_path"}, "--image-path"),
      Kept({"output_path"}, output_path),
      Value({"input_path"}, "--input-model"),
      Value({"Mapper.num_threads"}, "--ba-threads"),
      Value({"Mapper.init_min_num_inliers"}, "--init-min-inliers"),
      Value({"Mapper.init_min_tri_angle"}, "--init-min-tri-angle"),
      Value({"Mapper.abs_pose_min_num_inliers"}, "--abs-pose-min-inliers"),
      Value({"Mapper.abs_pose_max_error"}, "--abs-pose-max-error"),
      Value({"Mapper.filter_max_reproj_error"}, "--filter-max-error"),
      Value({"Mapper.tri_min_angle"}, "--min-tri-angle"),
      Value({"Mapper.ba_global_frames_ratio", "Mapper.ba_global_images_ratio"},
            "--ba-global-images-ratio"),
      FlagIfOn({"Mapper.tri_ignore_two_view_tracks"}, "--tri-ignore-two-view-tracks"),
      Value({"Mapper.tri_complete_max_transitivity"}, "--tri-complete-hops"),
      Value({"Mapper.random_seed"}, "--seed"),
      Value({"Mapper.ba_global_points_ratio"}, "--ba-global-points-ratio"),
      FlagIfOff({"Mapper.multiple_models"}, "--no-multiple-models"),
      FlagIfOff({"Mapper.ba_refine_focal_length"}, "--no-refine-intrinsics"),
      Ignored({"Mapper.ba_refine_principal_point"},
              "is decided by the final adjustment (docs/defaults.md, \"Principal point freed at "
              "the end\")"),
      Ignored({"Mapper.ba_refine_extra_params"}, "follows the focal length in Parallax"),
      Ignored({"Mapper.ba_global_function_tolerance", "Mapper.ba_local_function_tolerance",
               "Mapper.ba_global_max_num_iterations", "Mapper.ba_local_max_num_iterations"},
              "is not used: Parallax's adjustments stop on their own criteria"),
      Ignored({"Mapper.ba_use_gpu", "Mapper.ba_gpu_index"}, kNoGpu),
      Ignored({"Mapper.extract_colors"}, "is always on"),
      Ignored(OtherMapperOptions(), "is not used by Parallax's mapper (docs/colmap-dropin.md)"),
  };
}

// Where the mapper's models go: <output_path>/<k>/ (mapper, hierarchical_mapper) or the one
// model's files straight into <output_path> (point_triangulator, image_registrator).
enum class ModelLayout { kNumbered, kSingle };

// Runs `parallax mapper` into a folder beside `output_path`, then moves the models into place.
int RunMapperInto(const std::string& subcommand, const std::string& output_path,
                  ColmapTranslation translation, ModelLayout layout = ModelLayout::kNumbered) {
  namespace fs = std::filesystem;
  if (output_path.empty()) throw InputError("colmap " + subcommand + ": --output_path is required");
  const fs::path output(output_path);
  const fs::path staging = output.parent_path() / ("." + output.filename().string() + ".parallax");
  fs::remove_all(staging);
  translation.parallax_args.insert(translation.parallax_args.end(),
                                   {"--output", staging.string(), "--no-text"});
  const int code = RunTranslated(RunMapper, "mapper", translation);
  if (code == 0) {
    fs::create_directories(output);
    // Parallax writes OUT/sparse/<k>/; each model (or model 0's files) is moved into place.
    const fs::path models = staging / "sparse";
    const fs::path source = layout == ModelLayout::kSingle ? models / "0" : models;
    for (const fs::directory_entry& entry : fs::directory_iterator(source)) {
      const fs::path target = output / entry.path().filename();
      fs::remove_all(target);
      fs::rename(entry.path(), target);
    }
  }
  fs::remove_all(staging);
  return code;
}

// The value after `flag` in translated arguments; empty when absent.
std::string TranslatedValue(const ColmapTranslation& translation, const std::string& flag) {
  const auto& args = translation.parallax_args;
  const auto it = std::find(args.begin(), args.end(), flag);
  return it != args.end() && it + 1 != args.end() ? *(it + 1) : "";
}

// COLMAP's mapper leaves project.ini in each model folder, for its GUI to open the model with
// its database and images: the paths of the run (Parallax's mapper options are not COLMAP's).
void WriteProjectIni(const std::filesystem::path& output, const ColmapTranslation& translation) {
  const std::string ini = "database_path=" + TranslatedValue(translation, "--database") +
                          "\nimage_path=" + TranslatedValue(translation, "--image-path") +
                          "\ninput_path=" + TranslatedValue(translation, "--input-model") +
                          "\noutput_path=" + output.string() + "\n";
  for (const std::filesystem::directory_entry& model :
       std::filesystem::directory_iterator(output)) {
    if (model.is_directory() && HasColmapModel(model.path())) {
      WriteTextFileAtomically(model.path() / "project.ini", ini);
    }
  }
}

}  // namespace

int RunColmapMapper(int argc, char** argv) {
  std::string output_path;
  return Translate("mapper", argc, argv, MapperOptions(&output_path),
                   [&output_path](const ColmapTranslation& translation) {
                     const int code = RunMapperInto("mapper", output_path, translation);
                     if (code == 0) WriteProjectIni(output_path, translation);
                     return code;
                   });
}

int RunColmapHierarchicalMapper(int argc, char** argv) {
  std::string output_path;
  std::vector<ColmapOption> table = MapperOptions(&output_path);
  // 3.x names them bare, 4.x under HierarchicalMapper.
  table.push_back(Value({"HierarchicalMapper.leaf_max_num_images", "leaf_max_num_images"},
                        "--cluster-max-images"));
  table.push_back(
      Value({"HierarchicalMapper.image_overlap", "image_overlap"}, "--cluster-overlap"));
  table.push_back(
      Ignored({"HierarchicalMapper.num_workers", "num_workers", "HierarchicalMapper.num_threads"},
              "is set by --Mapper.num_threads and the cores"));
  table.push_back(
      Ignored({"HierarchicalMapper.init_num_trials", "HierarchicalMapper.is_hierarchical",
               "HierarchicalMapper.branching", "HierarchicalMapper.num_image_matches"},
              "is not used by Parallax's partition (docs/pair-selection.md)"));
  return Translate("hierarchical_mapper", argc, argv, table,
                   [&output_path](ColmapTranslation translation) {
                     translation.parallax_args.insert(translation.parallax_args.end(),
                                                      {"--mapper", "hierarchical"});
                     return RunMapperInto("hierarchical_mapper", output_path, translation);
                   });
}

int RunColmapPointTriangulator(int argc, char** argv) {
  std::string output_path;
  std::vector<ColmapOption> table = MapperOptions(&output_path);
  table.push_back(Custom({"clear_points"}, [](const std::string& value, std::vector<std::string>*) {
    if (!ParseColmapBool("clear_points", value)) {
      std::cerr << "colmap: warning: --clear_points 0: Parallax triangulates every point anew "
                   "from the database\n";
    }
  }));
  table.push_back(Ignored({"refine_intrinsics"},
                          "is not used: the intrinsics stay as given (run bundle_adjuster)"));
  return Translate(
      "point_triangulator", argc, argv, table, [&output_path](ColmapTranslation translation) {
        translation.parallax_args.push_back("--fixed-poses");
        return RunMapperInto("point_triangulator", output_path, translation, ModelLayout::kSingle);
      });
}

int RunColmapImageRegistrator(int argc, char** argv) {
  std::string output_path;
  return Translate("image_registrator", argc, argv, MapperOptions(&output_path),
                   [&output_path](const ColmapTranslation& translation) {
                     return RunMapperInto("image_registrator", output_path, translation,
                                          ModelLayout::kSingle);
                   });
}

int RunColmapBundleAdjuster(int argc, char** argv) {
  // COLMAP's booleans, passed on as Parallax's 0/1 option values.
  const auto boolean = [](std::string colmap_name, std::string parallax_flag) {
    return Custom(
        {"BundleAdjustment." + colmap_name},
        [colmap_name, parallax_flag](const std::string& value, std::vector<std::string>* args) {
          args->push_back(parallax_flag);
          args->push_back(ParseColmapBool(colmap_name, value) ? "1" : "0");
        });
  };
  const std::vector<ColmapOption> table = {
      Value({"input_path"}, "--input"),
      Value({"output_path"}, "--output"),
      boolean("refine_focal_length", "--refine-focal-length"),
      boolean("refine_principal_point", "--refine-principal-point"),
      boolean("refine_extra_params", "--refine-extra-params"),
      // 3.x refine_extrinsics, 4.x refine_rig_from_world: off holds every pose.
      FlagIfOff({"BundleAdjustment.refine_rig_from_world", "BundleAdjustment.refine_extrinsics"},
                "--fix-poses"),
      Value({"BundleAdjustmentCeres.max_num_iterations", "BundleAdjustment.max_num_iterations"},
            "--max-iterations"),
      Ignored({"BundleAdjustmentCeres.max_linear_solver_iterations",
               "BundleAdjustment.max_linear_solver_iterations",
               "BundleAdjustmentCeres.function_tolerance", "BundleAdjustment.function_tolerance",
               "BundleAdjustmentCeres.gradient_tolerance", "BundleAdjustment.gradient_tolerance",
               "BundleAdjustmentCeres.parameter_tolerance", "BundleAdjustment.parameter_tolerance",
               "BundleAdjustmentCeres.min_num_residuals_for_cpu_multi_threading",
               "BundleAdjustmentCeres.max_num_images_direct_dense_cpu_solver",
               "BundleAdjustmentCeres.max_num_images_direct_sparse_cpu_solver",
               "BundleAdjustment.backend"},
              "is decided by Parallax's solver (docs/defaults.md)"),
      Ignored({"BundleAdjustmentCeres.use_gpu", "BundleAdjustmentCeres.gpu_index",
               "BundleAdjustmentCeres.min_num_images_gpu_solver",
               "BundleAdjustmentCeres.max_num_images_direct_dense_gpu_solver",
               "BundleAdjustmentCeres.max_num_images_direct_sparse_gpu_solver"},
              kNoGpu),
      Ignored({"BundleAdjustment.refine_sensor_from_rig",
               "BundleAdjustment.constant_rig_from_world_rotation"},
              "applies to rigs, which Parallax does not model yet"),
      Ignored({"BundleAdjustment.refine_points3D", "BundleAdjustment.min_track_length"},
              "is not used: every point is adjusted"),
  };
  return Translate("bundle_adjuster", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.begin(), "adjust");
    translation.parallax_args.push_back("--no-text");  // COLMAP writes the binary model.
    return RunTranslated(RunModel, "model", translation);
  });
}

int RunColmapModelMerger(int argc, char** argv) {
  // COLMAP merges the second model into the first's frame.
  const std::vector<ColmapOption> table = {
      Value({"input_path1"}, "--into"),
      Value({"input_path2"}, "--input"),
      Value({"output_path"}, "--output"),
      Ignored({"max_reproj_error"}, "is not used: shared points are not fused"),
  };
  return Translate("model_merger", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.begin(), "merge");
    translation.parallax_args.push_back("--no-text");
    return RunTranslated(RunModel, "model", translation);
  });
}

int RunColmapDatabaseCreator(int argc, char** argv) {
  std::string database_path;
  const std::vector<ColmapOption> table = {
      Kept({"database_path"}, &database_path),
  };
  return Translate("database_creator", argc, argv, table,
                   [&database_path](const ColmapTranslation& translation) {
                     PrintWarnings(translation);
                     if (database_path.empty()) {
                       throw InputError("colmap database_creator: --database_path is required");
                     }
                     const Database database(database_path);  // Creates the schema.
                     std::cout << "database_creator: " << database_path << "\n";
                     return 0;
                   });
}

int RunColmapAutomaticReconstructor(int argc, char** argv) {
  const std::vector<ColmapOption> table = {
      Value({"workspace_path"}, "--output"),
      Value({"image_path"}, "--images"),
      Value({"camera_model"}, "--camera-model"),
      FlagIfOn({"single_camera"}, "--single-camera"),
      Custom({"camera_params"},
             [](const std::string& value, std::vector<std::string>* args) {
               if (value.empty()) return;
               args->push_back("--camera-params");
               args->push_back(value);
             }),
      Value({"num_threads"}, "--threads"),
      Value({"random_seed"}, "--seed"),
      Custom({"sparse"},
             [](const std::string& value, std::vector<std::string>*) {
               if (!ParseColmapBool("sparse", value)) {
                 throw InputError(
                     "colmap automatic_reconstructor: --sparse 0 leaves nothing to "
                     "do (Parallax has no dense stage)");
               }
             }),
      Ignored({"dense", "mesher"},
              "is not run: Parallax reconstructs the sparse model (run image_undistorter, then "
              "a dense tool)"),
      Ignored({"use_gpu", "gpu_index"}, kNoGpu),
      Ignored({"data_type", "quality"},
              "is not used: Parallax picks the pairs by the number of images"),
      Ignored({"vocab_tree_path"}, "is COLMAP's tree format: Parallax trains its own"),
      Ignored({"mask_path"}, "is not supported yet (masks)"),
      Ignored({"image_list_path", "single_camera_per_folder", "extraction", "matching", "feature",
               "mapper", "Mapper.ba_backend"},
              "is not used by Parallax's reconstruct"),
  };
  return Translate("automatic_reconstructor", argc, argv, table, [](ColmapTranslation translation) {
    // COLMAP's workspace: database.db and sparse/<k>/, as reconstruct writes.
    translation.parallax_args.push_back("--no-text");
    return RunTranslated(RunReconstruct, "reconstruct", translation);
  });
}

int RunColmapImageUndistorter(int argc, char** argv) {
  const std::vector<ColmapOption> table = {
      Value({"image_path"}, "--images"),
      Value({"input_path"}, "--model"),
      Value({"output_path"}, "--output"),
      Custom({"output_type"},
             [](const std::string& value, std::vector<std::string>*) {
               if (value != "COLMAP") {
                 throw InputError("colmap image_undistorter: --output_type " + value +
                                  " is not supported (COLMAP only)");
               }
             }),
      Value({"max_image_size"}, "--max-size"),
      Value({"blank_pixels"}, "--blank-pixels"),
      Ignored({"copy_policy", "num_patch_match_src_images"}, "is not used"),
  };
  return Translate("image_undistorter", argc, argv, table, [](const ColmapTranslation& t) {
    return RunTranslated(RunUndistort, "undistort", t);
  });
}

int RunColmapModelAligner(int argc, char** argv) {
  std::string alignment_type, database_path, ref_images_path;
  const std::vector<ColmapOption> table = {
      Value({"input_path"}, "--input"),
      Value({"output_path"}, "--output"),
      Kept({"alignment_type"}, &alignment_type),
      Kept({"database_path"}, &database_path),
      Kept({"ref_images_path"}, &ref_images_path),
      Custom({"ref_is_gps"},
             [](const std::string& value, std::vector<std::string>*) {
               if (ParseColmapBool("ref_is_gps", value)) {
                 throw InputError(
                     "colmap model_aligner: --ref_is_gps 1 is not supported: give "
                     "the GPS in the database and --alignment_type ecef or enu");
               }
             }),
      Value({"alignment_max_error", "robust_alignment_max_error"}, "--max-error"),
      Ignored({"min_common_images", "robust_alignment", "estimate_scale", "transform_path"},
              "is not used: the alignment is always a robust similarity (RANSAC, then a "
              "least-squares refit on its inliers) over all shared images"),
  };
  return Translate("model_aligner", argc, argv, table, [&](ColmapTranslation translation) {
    auto& args = translation.parallax_args;
    if (alignment_type == "plane") {
      args.push_back("--plane");
    } else if (alignment_type == "ecef" || alignment_type == "enu") {
      if (database_path.empty()) {
        throw InputError("colmap model_aligner: --alignment_type " + alignment_type +
                         " needs --database_path (its images' GPS positions)");
      }
      args.insert(args.end(), {"--gps", database_path, "--gps-frame", alignment_type});
    } else if (alignment_type == "custom" || (alignment_type.empty() && !ref_images_path.empty())) {
      if (ref_images_path.empty()) {
        throw InputError("colmap model_aligner: --alignment_type custom needs --ref_images_path");
      }
      args.insert(args.end(), {"--reference-positions", ref_images_path});
    } else {
      throw InputError("colmap model_aligner: --alignment_type " +
                       (alignment_type.empty() ? std::string("is required")
                                               : alignment_type + " is not supported") +
                       " (plane, ecef, enu or custom)");
    }
    args.insert(args.begin(), "align");
    args.push_back("--no-text");  // COLMAP writes the binary model.
    return RunTranslated(RunModel, "model", translation);
  });
}

int RunColmapModelConverter(int argc, char** argv) {
  const std::vector<ColmapOption> table = {
      Value({"input_path"}, "--input"),
      Value({"output_path"}, "--output"),
      Custom({"output_type"},
             [](const std::string& value, std::vector<std::string>* args) {
               const std::string type = value == "BIN"   ? "bin"
                                        : value == "TXT" ? "txt"
                                        : value == "PLY" ? "ply"
                                                         : "";
               if (type.empty()) {
                 throw InputError("colmap model_converter: --output_type " + value +
                                  " is not supported (BIN, TXT or PLY)");
               }
               args->push_back("--type");
               args->push_back(type);
             }),
      Ignored({"skip_distortion"}, "is not used"),
  };
  return Translate("model_converter", argc, argv, table, [](ColmapTranslation translation) {
    translation.parallax_args.insert(translation.parallax_args.begin(), "convert");
    return RunTranslated(RunModel, "model", translation);
  });
}

}  // namespace parallax::cli
