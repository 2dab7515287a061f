#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/cli/pipeline_options_cli.h"
#include "parallax/pipeline/database_stages.h"

namespace parallax::cli {

int RunFeatures(int argc, char** argv) {
  CLI::App app("Detect SIFT features in a folder of images and store them in a database",
               "parallax features");
  std::string image_dir, database_path;
  ExtractionStageOptions options;
  app.add_option("--images", image_dir, "Folder of images (not recursive)")->required();
  app.add_option("--database", database_path, "Database to create or resume (COLMAP format)")
      ->required();
  AddExtractionOptions(app, &options);
  app.add_option("--threads", options.num_threads, "Worker threads (-1: all cores)")
      ->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const ExtractionStageResult stats =
        ExtractFeaturesIntoDatabase(options, image_dir, database_path);
    std::cout << "features: " << stats.num_images_found << " images, " << stats.num_extracted
              << " extracted, " << stats.num_skipped << " already in the database, "
              << stats.failed.size() << " failed; mean "
              << static_cast<long>(stats.mean_num_keypoints + 0.5) << " keypoints; "
              << stats.seconds << " s" << std::endl;
    if (stats.num_extracted + stats.num_skipped == 0) {
      std::cerr << "error: no image could be read" << std::endl;
      return 1;
    }
    return 0;
  });
}

}  // namespace parallax::cli
