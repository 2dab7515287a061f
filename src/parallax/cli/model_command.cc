// parallax model convert|analyze|align|merge|adjust: tools for any COLMAP model.
#include <iostream>
#include <map>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/geometry/gps.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/report/model_union.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/scene/database.h"
#include "parallax/scene/principal_plane.h"
#include "parallax/util/check.h"

namespace parallax::cli {
namespace {

void WriteModelAs(const Reconstruction& model, const std::string& type,
                  const std::filesystem::path& output) {
  if (type == "bin") {
    WriteReconstructionBinary(model, output);
  } else if (type == "txt") {
    WriteReconstructionText(model, output);
  } else {
    WritePointsPly(model, output);
  }
}

// The camera centres the database's GPS priors give, in ECEF or in ENU metres about their mean
// position, by image name.
GroundTruth GpsGroundTruth(const std::filesystem::path& database_path, const std::string& frame) {
  if (!std::filesystem::is_regular_file(database_path)) {
    throw MissingFileError(database_path.string() + ": no such database");
  }
  const Database database(database_path);
  const std::vector<std::pair<image_t, GeodeticPosition>> priors = database.ReadImageGpsPriors();
  if (priors.size() < 3) {
    throw InputError(database_path.string() + ": " + std::to_string(priors.size()) +
                     " images have a GPS position; the alignment needs at least 3");
  }
  GeodeticPosition origin{0, 0, 0};
  for (const auto& [image_id, position] : priors) {
    origin.latitude += position.latitude / priors.size();
    origin.longitude += position.longitude / priors.size();
    origin.altitude += position.altitude / priors.size();
  }
  std::map<image_t, std::string> names;
  for (const Image& image : database.ReadAllImages()) names[image.image_id] = image.name;
  std::vector<std::pair<std::string, Eigen::Vector3d>> centers;
  for (const auto& [image_id, position] : priors) {
    centers.emplace_back(names.at(image_id), frame == "ecef" ? EcefFromGeodetic(position)
                                                             : EnuFromGeodetic(position, origin));
  }
  return GroundTruthOfPositions(centers, database_path.string() + " (GPS, " + frame + ")");
}

}  // namespace

int RunModel(int argc, char** argv) {
  CLI::App app("Tools for any COLMAP model (Parallax's or COLMAP's)", "parallax model");
  app.require_subcommand(1);
  // -q and -v are the group's: subcommands pass them up (`parallax model analyze M -q`).
  app.fallthrough();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);

  std::string input, output, type, reference, base;
  bool json = false;
  CLI::App* convert = app.add_subcommand("convert", "Rewrite a model as binary, text or PLY");
  convert->add_option("--input", input, "Model folder")->required();
  convert->add_option("--output", output, "Folder (bin, txt) or file (ply) to write")->required();
  convert->add_option("--type", type, "bin, txt or ply")
      ->required()
      ->check(CLI::IsMember({"bin", "txt", "ply"}));

  CLI::App* analyze = app.add_subcommand(
      "analyze", "Print a model's numbers: images, points, observations, track lengths, errors");
  analyze->add_option("input", input, "Model folder")->required();
  analyze->add_flag("--json", json, "As JSON (the fields of summary.json)");

  CLI::App* align = app.add_subcommand(
      "align",
      "Move a model into the frame of a reference (ground truth or another model) by the "
      "similarity of their camera centres (RANSAC), or lay its principal plane on z = 0 "
      "(--plane), and write it");
  align->add_option("--input", input, "Model folder")->required();
  CLI::Option* reference_option =
      align->add_option("--reference", reference,
                        "Ground truth (*_par.txt, a folder of *.camera files) or a model folder; "
                        "images are matched by name");
  std::string reference_positions, gps_database, gps_frame = "enu";
  CLI::Option* positions_option =
      align->add_option("--reference-positions", reference_positions,
                        "Or camera centres: per line `image_name X Y Z` (COLMAP's model_aligner "
                        "--alignment_type custom --ref_images_path)");
  CLI::Option* gps_option =
      align->add_option("--gps", gps_database,
                        "Or the GPS positions the database holds (EXIF or COLMAP 4's pose "
                        "priors), in metres: see --gps-frame (COLMAP's ecef and enu alignments)");
  align
      ->add_option("--gps-frame", gps_frame,
                   "ecef (earth-centred metres) or enu (east, north, up metres about the mean "
                   "position)")
      ->capture_default_str()
      ->check(CLI::IsMember({"ecef", "enu"}));
  EvaluationOptions alignment;
  align
      ->add_option("--max-error", alignment.alignment_max_error,
                   "Inlier distance of the alignment, in the reference's units (metres for "
                   "--gps); 0: 5 % of the reference's spread (COLMAP's --alignment_max_error)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  reference_option->excludes(positions_option)->excludes(gps_option);
  positions_option->excludes(gps_option);
  bool plane = false, no_text = false;
  align
      ->add_flag("--plane", plane,
                 "Instead: the points' plane of largest spread onto z = 0, centroid at the "
                 "origin, cameras above (COLMAP's model_aligner --alignment_type plane)")
      ->excludes(reference_option)
      ->excludes(positions_option)
      ->excludes(gps_option);
  align->add_flag("--no-text", no_text, "Write the binary model only");
  align->add_option("--output", output, "Folder of the aligned model (binary and text)")
      ->required();

  CLI::App* merge = app.add_subcommand(
      "merge",
      "Add a model to another that shares images with it: it is moved into the other's frame "
      "by the similarity of the shared camera centres; its other images and their points join");
  merge->add_option("--input", input, "Model folder to add")->required();
  merge->add_option("--into", base, "Model folder it joins (its frame and shared poses stay)")
      ->required();
  merge->add_option("--output", output, "Folder of the merged model (binary and text)")->required();
  merge->add_flag("--no-text", no_text, "Write the binary model only");

  CLI::App* adjust = app.add_subcommand(
      "adjust",
      "Bundle-adjust a model as a whole: poses, points and the chosen intrinsics (COLMAP's "
      "bundle_adjuster); the first pose and the scale stay");
  adjust->add_option("--input", input, "Model folder")->required();
  adjust->add_option("--output", output, "Folder of the adjusted model")->required();
  // COLMAP's bundle_adjuster defaults: focal length and distortion free, principal point
  // fixed, squared loss.
  BundleAdjustmentOptions ba;
  ba.refine_focal_length = true;
  ba.refine_extra_params = true;
  ba.loss_function = LossFunctionType::kTrivial;
  bool fix_poses = false;
  adjust->add_option("--refine-focal-length", ba.refine_focal_length, "Free the focal lengths")
      ->capture_default_str();
  adjust
      ->add_option("--refine-principal-point", ba.refine_principal_point,
                   "Free the principal points")
      ->capture_default_str();
  adjust
      ->add_option("--refine-extra-params", ba.refine_extra_params,
                   "Free the distortion parameters")
      ->capture_default_str();
  adjust->add_flag("--fix-poses", fix_poses, "Hold every pose: only points and intrinsics move");
  adjust->add_option("--max-iterations", ba.max_num_iterations, "Levenberg-Marquardt iterations")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  adjust
      ->add_option_function<std::string>(
          "--loss",
          [&ba](const std::string& name) {
            ba.loss_function = LossFunctionTypeFromName(name).value();
          },
          "squared, huber, soft-l1 or cauchy")
      ->check(CLI::IsMember({"cauchy", "huber", "soft-l1", "squared"}))
      ->default_str("squared");
  adjust
      ->add_option("--loss-scale", ba.loss_scale_px,
                   "Scale of a robust loss, pixels of reprojection error")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  adjust->add_option("--threads", ba.num_threads, "Threads (-1: all cores)")->capture_default_str();
  adjust->add_flag("--no-text", no_text, "Write the binary model only");

  return RunCommand(app, argc, argv, flags, [&] {
    const Reconstruction model = ReadReconstruction(input);
    if (*convert) {
      WriteModelAs(model, type, output);
      std::cout << "model convert: " << input << " -> " << output << " (" << type << ")\n";
    } else if (*analyze) {
      const nlohmann::json statistics = ModelStatisticsToJson(model);
      if (json) {
        std::cout << statistics.dump(2) << "\n";
      } else {
        for (const auto& [key, value] : statistics.items()) {
          if (key != "track_length_histogram") std::cout << key << ": " << value << "\n";
        }
        std::cout << "points by track length:";
        for (const nlohmann::json& bin : statistics["track_length_histogram"]) {
          std::cout << " " << bin["length"] << ":" << bin["points"];
        }
        std::cout << "\n";
      }
    } else if (*merge) {
      ModelUnionReport report;
      const Reconstruction united = UniteModels(ReadReconstruction(base), base, model, &report);
      WriteReconstructionBinary(united, output);
      if (!no_text) WriteReconstructionText(united, output);
      std::cout << "model merge: " << report.num_shared_images << " shared images ("
                << report.num_alignment_inliers << " agree, scale " << report.scale << "); "
                << report.num_images_added << " images and " << report.num_points_added
                << " points added; " << united.NumRegImages() << " images, " << united.NumPoints3D()
                << " points -> " << output << "\n";
    } else if (*adjust) {
      Reconstruction adjusted = model;
      const double error_before = adjusted.UpdatePointErrors();
      const BundleAdjustmentSummary summary =
          BundleAdjust(ba, WholeModelConfig(adjusted, fix_poses), &adjusted);
      if (!summary.success) {
        throw InputError("model adjust: " + input + ": the adjustment failed (" +
                         summary.termination + ")");
      }
      const double error_after = adjusted.UpdatePointErrors();
      WriteReconstructionBinary(adjusted, output);
      if (!no_text) WriteReconstructionText(adjusted, output);
      std::cout << "model adjust: " << adjusted.NumRegImages() << " images, "
                << adjusted.NumPoints3D() << " points, " << summary.num_iterations
                << " iterations (" << summary.solver << "); mean reprojection error "
                << error_before << " -> " << error_after << " px -> " << output << "\n";
    } else if (plane) {
      Reconstruction aligned = model;
      const Sim3d aligned_from_model = PrincipalPlaneAlignment(model);
      aligned.Transform(aligned_from_model);
      WriteReconstructionBinary(aligned, output);
      if (!no_text) WriteReconstructionText(aligned, output);
      std::cout << "model align: principal plane of " << model.NumPoints3D()
                << " points onto z = 0 -> " << output << "\n";
    } else {
      const GroundTruth truth =
          !reference.empty()             ? ReadGroundTruth(reference)
          : !reference_positions.empty() ? ReadPositionsGroundTruth(reference_positions)
          : !gps_database.empty()        ? GpsGroundTruth(gps_database, gps_frame)
                                         : throw InputError(
                                               "model align: give --reference, --reference-positions, "
                                                      "--gps or --plane");
      EvaluationMetrics metrics;
      const Reconstruction aligned = AlignToReference(model, truth, &metrics, alignment);
      WriteReconstructionBinary(aligned, output);
      if (!no_text) WriteReconstructionText(aligned, output);
      std::cout << "model align: scale " << metrics.gt_from_model.scale << ", "
                << metrics.num_alignment_inliers << "/" << metrics.num_registered_in_gt
                << " shared images agree; median centre error " << metrics.center_error.median;
      // Positions carry no rotations to compare with.
      if (!reference.empty())
        std::cout << ", rotation " << metrics.rotation_error_deg.median << " deg";
      std::cout << " -> " << output << "\n";
    }
    std::cout << std::flush;
    return 0;
  });
}

}  // namespace parallax::cli
