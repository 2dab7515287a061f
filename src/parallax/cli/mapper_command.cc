#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/cli/mapper_options_cli.h"
#include "parallax/pipeline/database_stages.h"
#include "parallax/util/check.h"

namespace parallax::cli {

int RunMapper(int argc, char** argv) {
  CLI::App app("Run the incremental mapper on an existing database (Parallax's or COLMAP's)",
               "parallax mapper");
  std::string database_path, image_path, output;
  MappingStageOptions options;
  app.add_option("--database", database_path, "Feature and match database")->required();
  app.add_option("--image-path", image_path,
                 "Folder of the images, for point colours the database did not store (without "
                 "it those points stay black, as COLMAP's image_registrator leaves them)");
  app.add_option("--output", output, "Output folder (sparse/<k>/, points.ply, summary.json)")
      ->required();
  AddSeedOption(app, &options.mapper.seed);
  app.add_option("--cluster", options.cluster_file,
                 "Map only the images and pairs of this cluster file (as the hierarchical "
                 "mapper writes them to OUT/clusters/)");
  AddMapperOptions(app, &options);
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    if (!options.cluster_file.empty() && options.mapper_type == MapperType::kHierarchical) {
      throw InputError(
          "--cluster maps one cluster incrementally; it cannot be combined with "
          "--mapper hierarchical");
    }
    const MappingStageResult result = MapDatabase(options, database_path, image_path, output);
    PrintMappingResult(result, output);
    if (result.models.empty()) {
      std::cerr << "error: no model could be started: " << result.summary.failure << std::endl;
      return 1;
    }
    return 0;
  });
}

}  // namespace parallax::cli
