// parallax export: a model in the formats of nerfstudio, Bundler, VisualSfM, or as a PLY with
// the cameras.
#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/export/model_export_format.h"
#include "parallax/scene/colmap_io.h"

namespace parallax::cli {

int RunExport(int argc, char** argv) {
  CLI::App app(
      "Write a model in another tool's format: nerfstudio (transforms.json, OpenGL axes, with "
      "sparse_pc.ply beside it), ply (points and camera frustums), bundler (bundle.out and "
      "list.txt beside it) or nvm (VisualSfM)",
      "parallax export");
  std::string model_path, format, output;
  NerfstudioExportOptions nerfstudio;
  app.add_option("--model", model_path, "Model folder (e.g. OUT/sparse/0)")->required();
  app.add_option("--format", format, "nerfstudio, ply, bundler or nvm")
      ->required()
      ->check(CLI::IsMember({"nerfstudio", "ply", "bundler", "nvm"}));
  app.add_option("--output", output, "File to write (transforms.json, model.ply, bundle.out, ...)")
      ->required();
  app.add_option("--image-prefix", nerfstudio.image_prefix,
                 "nerfstudio: prefix of each frame's file_path, relative to transforms.json")
      ->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const Reconstruction model = ReadReconstruction(model_path);
    ExportModel(model, format, output, nerfstudio);
    std::cout << "export: " << model.NumRegImages() << " images, " << model.NumPoints3D()
              << " points -> " << output << " (" << format << ")" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
