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
#include "parallax/util/check.h"

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

// Runs a Parallax subcommand on translated arguments, after the warnings.
int RunTranslated(int (*run)(int, char**), const std::string& parallax_command,
                  const ColmapTranslation& translation) {
  for (const std::string& warning : translation.warnings) {
    std::cerr << "colmap: warning: " << warning << std::endl;
  }
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

// COLMAP's mapper options, for mapper and hierarchical_mapper; `output_path` is kept aside:
// both write <output_path>/<k>/ where Parallax writes OUT/sparse/<k>/.
std::vector<ColmapOption> MapperOptions(std::string* output_path) {
  return {
      Value({"database_path"}, "--database"),
      Value({"image_path"}, "--image-path"),
      Custom({"output_path"}, [output_path](const std::string& value,
                                            std::vector<std::string>*) { *output_path = value; }),
      Value({"input_path"}, "--input-model"),
      Value({"Mapper.num_threads"}, "--ba-threads"),
      Value({"Mapper.init_min_num_inliers"}, "--init-min-inliers"),
      Value({"Mapper.init_min_tri_angle"}, "--init-min-tri-angle"),
      Value({"Mapper.abs_pose_min_num_inliers"}, "--abs-pose-min-inliers"),
      Value({"Mapper.abs_pose_max_error"}, "--abs-pose-max-error"),
      Value({"Mapper.filter_max_reproj_error"}, "--filter-max-error"),
      Value({"Mapper.tri_min_angle"}, "--min-tri-angle"),
      Value({"Mapper.ba_global_images_ratio"}, "--ba-global-images-ratio"),
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
  };
}

// Runs `parallax mapper` into a folder beside `output_path`, then moves each model into place.
int RunMapperInto(const std::string& subcommand, const std::string& output_path,
                  ColmapTranslation translation) {
  namespace fs = std::filesystem;
  if (output_path.empty()) throw InputError("colmap " + subcommand + ": --output_path is required");
  // Parallax writes OUT/sparse/<k>; COLMAP writes <output_path>/<k>. Mapped beside, then
  // each model moved into place.
  const fs::path output(output_path);
  const fs::path staging = output.parent_path() / ("." + output.filename().string() + ".parallax");
  fs::remove_all(staging);
  translation.parallax_args.insert(translation.parallax_args.end(),
                                   {"--output", staging.string(), "--no-text"});
  const int code = RunTranslated(RunMapper, "mapper", translation);
  if (code == 0) {
    fs::create_directories(output);
    for (const fs::directory_entry& model : fs::directory_iterator(staging / "sparse")) {
      const fs::path target = output / model.path().filename();
      fs::remove_all(target);
      fs::rename(model.path(), target);
    }
  }
  fs::remove_all(staging);
  return code;
}

}  // namespace

int RunColmapMapper(int argc, char** argv) {
  std::string output_path;
  return Translate("mapper", argc, argv, MapperOptions(&output_path),
                   [&output_path](const ColmapTranslation& translation) {
                     return RunMapperInto("mapper", output_path, translation);
                   });
}

int RunColmapHierarchicalMapper(int argc, char** argv) {
  std::string output_path;
  std::vector<ColmapOption> table = MapperOptions(&output_path);
  table.push_back(Value({"leaf_max_num_images"}, "--cluster-max-images"));
  table.push_back(Value({"image_overlap"}, "--cluster-overlap"));
  table.push_back(Ignored({"num_workers"}, "is set by --Mapper.num_threads and the cores"));
  return Translate("hierarchical_mapper", argc, argv, table,
                   [&output_path](ColmapTranslation translation) {
                     translation.parallax_args.insert(translation.parallax_args.end(),
                                                      {"--mapper", "hierarchical"});
                     return RunMapperInto("hierarchical_mapper", output_path, translation);
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
  const std::vector<ColmapOption> table = {
      Value({"input_path"}, "--input"),
      Value({"output_path"}, "--output"),
      Custom({"alignment_type"},
             [](const std::string& value, std::vector<std::string>* args) {
               if (value != "plane") {
                 throw InputError("colmap model_aligner: --alignment_type " + value +
                                  " is not supported yet (plane)");
               }
               args->push_back("--plane");
             }),
      Ignored({"database_path"}, "is not needed by the plane alignment"),
      Ignored({"alignment_max_error", "min_common_images", "robust_alignment",
               "robust_alignment_max_error", "estimate_scale"},
              "applies to alignment to reference positions, not to the plane"),
  };
  return Translate("model_aligner", argc, argv, table, [](ColmapTranslation translation) {
    const auto& args = translation.parallax_args;
    if (std::find(args.begin(), args.end(), "--plane") == args.end()) {
      throw InputError("colmap model_aligner: --alignment_type is required (plane)");
    }
    translation.parallax_args.insert(translation.parallax_args.begin(), "align");
    translation.parallax_args.push_back("--no-text");  // COLMAP writes the binary model.
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
