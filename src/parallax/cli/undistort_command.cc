// parallax undistort: COLMAP's dense workspace (undistorted PINHOLE images and model) for
// multi-view stereo, NeRF and Gaussian splatting.
#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/export/image_undistortion.h"
#include "parallax/scene/colmap_io.h"

namespace parallax::cli {

int RunUndistort(int argc, char** argv) {
  CLI::App app(
      "Undistort a model's photos into COLMAP's dense workspace: OUT/images (PINHOLE, same "
      "names), OUT/sparse (the model in undistorted coordinates), OUT/stereo (patch-match.cfg, "
      "fusion.cfg). What colmap patch_match_stereo, OpenMVS, nerfstudio and 3D Gaussian "
      "splatting read.",
      "parallax undistort");
  std::string model_path, image_dir, output_dir;
  UndistortionOptions options;
  app.add_option("--model", model_path, "Model folder (e.g. OUT/sparse/0)")->required();
  app.add_option("--images", image_dir, "Folder of the model's photos")->required();
  app.add_option("--output", output_dir, "Workspace folder to write")->required();
  app.add_option("--max-size", options.max_image_size,
                 "Longest side of the undistorted images (larger ones are scaled down; <= 0: "
                 "no limit)")
      ->capture_default_str();
  app.add_option("--blank-pixels", options.blank_pixels,
                 "0: crop to pixels that all come from the photo; 1: keep all of the photo, "
                 "with black where it shows nothing")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--jpeg-quality", options.jpeg_quality, "Quality of JPEG outputs")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--threads", options.num_threads, "Worker threads (-1: all cores)")
      ->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    const Reconstruction model = ReadReconstruction(model_path);
    const UndistortionResult result =
        WriteUndistortedWorkspace(model, image_dir, output_dir, options);
    std::cout << "undistort: " << result.num_images << " images into " << output_dir << " ("
              << result.seconds << " s)" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
