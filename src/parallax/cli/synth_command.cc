#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/pipeline/camera_setup.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/util/check.h"
#include "parallax/util/timer.h"

namespace parallax::cli {

int RunSynth(int argc, char** argv) {
  CLI::App app(
      "Render a synthetic temple scene with exact cameras (images, <name>_par.txt, K.txt, "
      "gt/ COLMAP model)",
      "parallax synth");
  std::string output_dir, layout = "ring", antialiasing = "quincunx";
  SyntheticSceneOptions options;
  bool no_shadows = false;
  app.add_option("--output", output_dir, "Folder to write the views and cameras into")->required();
  app.add_option("--views", options.num_views, "Number of views")
      ->capture_default_str()
      ->check(CLI::Range(2, 100000));
  app.add_option("--layout", layout,
                 "ring (around one temple), hemisphere (a spiral above it), sequence (a walk "
                 "past a row of temples, for sequential matching), aerial (a drone survey of a "
                 "town in strips: JPEG with EXIF focal length and GPS, gt/overlap_pairs.txt), "
                 "or a hard scene (with gt/overlap_pairs.txt): street (walking down a street "
                 "between two rows of temples, looking forward at eye height: small "
                 "triangulation angles), twin (an orbit around two identical temples on "
                 "different ground: repeated structure) or weak (arcs around two temples joined "
                 "by 2 to 4 views that see both: a barely linked view graph)")
      ->capture_default_str()
      ->check(
          CLI::IsMember({"ring", "hemisphere", "sequence", "aerial", "street", "twin", "weak"}));
  app.add_option("--oblique", options.oblique_fraction,
                 "aerial: share of the views tilted 30 degrees off nadir")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option(
         "--gps-noise", options.gps_noise,
         "aerial: standard deviation in metres of the EXIF GPS noise (twice that in height)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  std::string image_size;
  app.add_option("--image-size", image_size, "Image size WxH (sets --width and --height)")
      ->check(DimensionsValidator("640x480"));
  app.add_option("--width", options.width, "Image width in pixels")
      ->capture_default_str()
      ->check(CLI::Range(16, 20000));
  app.add_option("--height", options.height, "Image height in pixels")
      ->capture_default_str()
      ->check(CLI::Range(16, 20000));
  app.add_option("--focal", options.focal_length, "Focal length in pixels (0: 0.9 * width)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  std::string camera_model = "PINHOLE", camera_params;
  app.add_option("--camera", camera_model,
                 "The lens, any COLMAP camera model (OPENCV_FISHEYE, EQUIRECTANGULAR, ...), "
                 "rendered ray per pixel through the model")
      ->capture_default_str();
  app.add_option("--camera-params", camera_params,
                 "The lens's parameters in COLMAP's order, comma-separated (default: the "
                 "focal length, the image centre, no distortion)");
  app.add_option("--fov", options.field_of_view,
                 "Field of view across the width in degrees, instead of --focal (a fisheye's "
                 "may exceed 180)")
      ->check(CLI::PositiveNumber)
      ->excludes("--focal");
  app.add_flag("--exif", options.write_exif,
               "Write JPEG views with EXIF focal length and sensor size, as a camera does");
  app.add_option("--seed", options.seed, "Seed of textures, poses, lighting and noise")
      ->capture_default_str();
  app.add_option("--noise", options.noise_stddev, "Pixel noise standard deviation in grey levels")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--blur", options.blur_sigma, "Gaussian blur sigma in pixels")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--lighting", options.lighting_variation,
                 "Per-view lighting change in [0, 1] (sun direction and exposure)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--antialiasing", antialiasing, "none, quincunx (2 rays per pixel) or grid3x3")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "quincunx", "grid3x3"}));
  app.add_flag("--no-shadows", no_shadows, "Do not cast sun shadows");
  app.add_option("--name", options.name, "Prefix of the camera file <name>_par.txt")
      ->capture_default_str();
  app.add_option("--threads", options.num_threads, "Worker threads (-1: all cores)")
      ->capture_default_str();
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    options.layout = SyntheticSceneLayoutFromName(layout);
    options.camera_model = CameraModelIdFromName(camera_model);
    if (options.camera_model == CameraModelId::kInvalid) {
      throw InputError("--camera: unknown camera model '" + camera_model + "'");
    }
    if (!camera_params.empty()) options.camera_params = ParseCameraParams(camera_params);
    if (!image_size.empty()) ParseDimensions(image_size, &options.width, &options.height);
    options.antialiasing = AntialiasingFromName(antialiasing);
    options.shadows = !no_shadows;
    const Timer timer;
    const Reconstruction views = GenerateSyntheticScene(options, output_dir);
    std::cout << "synth: " << views.NumImages() << " views (" << layout << ", " << options.width
              << "x" << options.height << ", " << views.GetCamera(1).ModelName();
    if (views.GetCamera(1).Projection() != CameraProjection::kSpherical) {
      std::cout << ", f = " << options.EffectiveFocalLength() << " px";
    }
    std::cout << ") in " << output_dir << "; cameras in "
              << (IsPinholeCameraModel(views.GetCamera(1).model_id)
                      ? options.name + "_par.txt, K.txt, gt/; "
                      : std::string("gt/; "))
              << timer.ElapsedSeconds() << " s" << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
