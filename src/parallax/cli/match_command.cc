#include <iomanip>
#include <iostream>
#include <map>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/cli/pipeline_options_cli.h"
#include "parallax/pipeline/database_stages.h"
#include "parallax/pipeline/run_summary.h"

namespace parallax::cli {
namespace {

const char* ConfigName(int config) {
  switch (config) {
    case TwoViewGeometry::kUndefined:
      return "undefined";
    case TwoViewGeometry::kDegenerate:
      return "degenerate";
    case TwoViewGeometry::kCalibrated:
      return "calibrated";
    case TwoViewGeometry::kUncalibrated:
      return "uncalibrated";
    case TwoViewGeometry::kPlanar:
      return "planar";
    case TwoViewGeometry::kPanoramic:
      return "panoramic";
    case TwoViewGeometry::kPlanarOrPanoramic:
      return "planar_or_panoramic";
    case TwoViewGeometry::kWatermark:
      return "watermark";
    case TwoViewGeometry::kMultiple:
      return "multiple";
    default:
      return "unknown";
  }
}

// Per image keypoints and per pair putative/inlier counts of the whole database.
void PrintStatsTables(const Database& database) {
  std::map<image_t, std::string> names;
  std::cout << "# image_id  keypoints  name\n";
  for (const Image& image : database.ReadAllImages()) {
    names[image.image_id] = image.name;
    std::cout << std::setw(10) << image.image_id << std::setw(11)
              << database.NumKeypoints(image.image_id) << "  " << image.name << "\n";
  }
  std::map<image_pair_t, size_t> putative;
  for (const auto& [pair_id, matches] : database.ReadAllMatches())
    putative[pair_id] = matches.size();
  std::cout << "# image1  image2  putative  inliers  config  name1  name2\n";
  for (const auto& [pair_id, geometry] : database.ReadTwoViewGeometries()) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const auto it = putative.find(pair_id);
    std::cout << std::setw(8) << image_id1 << std::setw(8) << image_id2 << std::setw(10)
              << (it == putative.end() ? 0 : it->second) << std::setw(9)
              << geometry.inlier_matches.size() << "  " << ConfigName(geometry.config) << "  "
              << names[image_id1] << "  " << names[image_id2] << "\n";
  }
  std::cout << std::flush;
}

}  // namespace

int RunMatch(int argc, char** argv) {
  CLI::App app("Match features between image pairs and verify them geometrically",
               "parallax match");
  std::string database_path;
  MatchingStageOptions options;
  bool print_stats = false;
  app.add_option("--database", database_path, "Database with features (parallax features)")
      ->required();
  AddMatchingOptions(app, &options);
  app.add_option("--threads", options.num_threads, "Worker threads (-1: all cores)")
      ->capture_default_str();
  AddSeedOption(app, &options.seed);
  app.add_flag("--stats", print_stats,
               "Print per image keypoints and per pair putative matches and inliers, then the "
               "matching summary (pairs considered, matched, stopped by the preemptive test, "
               "verified) as JSON");
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const MatchingStageResult stats = MatchDatabase(options, database_path);
    if (print_stats) {
      PrintStatsTables(Database(database_path));
      std::cout << MatchingSummary(stats).dump(2) << "\n";
    }
    std::cout << "match: " << stats.num_pairs << " pairs, " << stats.num_matched << " matched, "
              << stats.num_skipped << " already verified, " << stats.num_verified << " verified, "
              << stats.num_preemptive_rejected << " stopped by the preemptive test; "
              << stats.seconds << " s" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
