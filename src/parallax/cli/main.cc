// parallax: incremental Structure from Motion. Dispatches to one subcommand per stage.
#include <cstring>
#include <iostream>
#include <string>

#include "parallax/cli/commands.h"
#include "parallax/cli/process_setup.h"

namespace {

struct Command {
  const char* name;
  const char* description;
  int (*run)(int argc, char** argv);
};

// The table of subcommands, in the order a user meets them.
constexpr Command kCommands[] = {
    {"demo", "Synthesise a scene, reconstruct and evaluate it (no data needed)",
     parallax::cli::RunDemo},
    {"reconstruct", "Photos to cameras and points: features, matching, mapping",
     parallax::cli::RunReconstruct},
    {"features", "Detect SIFT features in a folder of images", parallax::cli::RunFeatures},
    {"match", "Match and verify image pairs in a database", parallax::cli::RunMatch},
    {"mapper", "Run the incremental mapper on an existing database", parallax::cli::RunMapper},
    {"evaluate", "Compare a model's camera poses with ground truth", parallax::cli::RunEvaluate},
    {"report", "Write a self-contained HTML report of a run", parallax::cli::RunReport},
    {"model", "Model tools: convert (bin, txt, ply), analyze, align, merge",
     parallax::cli::RunModel},
    {"export", "Write a model for nerfstudio, Bundler, VisualSfM, or as a PLY with cameras",
     parallax::cli::RunExport},
    {"undistort", "Undistorted images and model for dense reconstruction, NeRF, splatting",
     parallax::cli::RunUndistort},
    {"calibrate", "Calibrate a camera from chessboard photos", parallax::cli::RunCalibrate},
    {"synth", "Render a synthetic temple scene with exact cameras", parallax::cli::RunSynth},
    {"version", "Print the version", parallax::cli::RunVersion},
};

void PrintUsage() {
  std::cout << "Parallax: incremental Structure from Motion.\n\n"
               "Usage: parallax <command> [options]\n"
               "       parallax <command> --help\n\nCommands:\n";
  for (const Command& command : kCommands) {
    std::string name = command.name;
    name.resize(14, ' ');
    std::cout << "  " << name << command.description << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  parallax::cli::PrepareProcess();
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintUsage();
    return argc < 2 ? 1 : 0;
  }
  for (const Command& command : kCommands) {
    if (std::strcmp(argv[1], command.name) == 0) return command.run(argc - 1, argv + 1);
  }
  std::cerr << "error: unknown command '" << argv[1] << "' (see parallax --help)" << std::endl;
  return 2;
}
