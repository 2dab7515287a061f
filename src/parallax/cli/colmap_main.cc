// colmap: Parallax under COLMAP's command line, for scripts that call a `colmap` executable
// (Gaussian splatting's convert.py, instant-ngp's colmap2nerf.py, nerfstudio). It never needs
// a display or a GPU.
#include <cstring>
#include <iostream>

#include "parallax/cli/colmap_commands.h"
#include "parallax/cli/process_setup.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int argc, char** argv);
};

constexpr Command kCommands[] = {
    {"feature_extractor", parallax::cli::RunColmapFeatureExtractor},
    {"exhaustive_matcher", parallax::cli::RunColmapExhaustiveMatcher},
    {"sequential_matcher", parallax::cli::RunColmapSequentialMatcher},
    {"vocab_tree_matcher", parallax::cli::RunColmapVocabTreeMatcher},
    {"spatial_matcher", parallax::cli::RunColmapSpatialMatcher},
    {"matches_importer", parallax::cli::RunColmapMatchesImporter},
    {"mapper", parallax::cli::RunColmapMapper},
    {"hierarchical_mapper", parallax::cli::RunColmapHierarchicalMapper},
    {"image_undistorter", parallax::cli::RunColmapImageUndistorter},
    {"model_aligner", parallax::cli::RunColmapModelAligner},
    {"model_analyzer", parallax::cli::RunColmapModelAnalyzer},
    {"model_converter", parallax::cli::RunColmapModelConverter},
    {"model_merger", parallax::cli::RunColmapModelMerger},
    {"point_triangulator", parallax::cli::RunColmapPointTriangulator},
    {"image_registrator", parallax::cli::RunColmapImageRegistrator},
    {"bundle_adjuster", parallax::cli::RunColmapBundleAdjuster},
    {"database_creator", parallax::cli::RunColmapDatabaseCreator},
    {"automatic_reconstructor", parallax::cli::RunColmapAutomaticReconstructor},
};

void PrintUsage() {
  std::cout << "COLMAP's command line on Parallax (Parallax's own: parallax --help).\n\n"
               "Usage: colmap <command> [options]\n\nCommands:\n";
  for (const Command& command : kCommands) std::cout << "  " << command.name << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  parallax::cli::PrepareProcess();
  if (argc < 2 || std::strcmp(argv[1], "-h") == 0 || std::strcmp(argv[1], "--help") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintUsage();
    return argc < 2 ? 1 : 0;
  }
  for (const Command& command : kCommands) {
    if (std::strcmp(argv[1], command.name) == 0) return command.run(argc - 1, argv + 1);
  }
  std::cerr << "error: unknown command '" << argv[1] << "' (see colmap help)" << std::endl;
  return 1;
}
