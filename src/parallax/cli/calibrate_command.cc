// parallax calibrate: intrinsics from photos of a printed chessboard, written to camera.json.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "parallax/calibration/camera_json.h"
#include "parallax/calibration/checkerboard_calibration.h"
#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/util/check.h"

namespace parallax::cli {
namespace {

void PrintImages(const CheckerboardCalibrationResult& result) {
  std::vector<const CheckerboardImageResult*> used, skipped;
  size_t name_width = 8;
  for (const CheckerboardImageResult& image : result.images) {
    (image.status == CheckerboardImageStatus::kUsed ? used : skipped).push_back(&image);
    name_width = std::max(name_width, image.path.filename().string().size());
  }
  const auto name = [&](const CheckerboardImageResult& image) {
    std::string text = image.path.filename().string();
    text.resize(name_width + 2, ' ');
    return text;
  };
  std::cout << "Used images (" << used.size() << "), RMS reprojection error per image:\n";
  for (const CheckerboardImageResult* image : used) {
    std::cout << "  " << name(*image) << std::fixed << std::setprecision(3) << image->rms_error
              << " px\n";
  }
  std::cout << "Skipped images (" << skipped.size() << "):\n";
  for (const CheckerboardImageResult* image : skipped) {
    std::cout << "  " << name(*image) << CheckerboardImageStatusName(image->status) << ": "
              << image->reason << "\n";
  }
}

void PrintIntrinsics(const CheckerboardCalibrationResult& result, bool fit_k3) {
  std::cout << std::fixed << std::setprecision(3) << "\nImage size: " << result.width << "x"
            << result.height << "\nRMS reprojection error: " << result.rms_error << " px over "
            << result.num_used_images << " images\n";
  const auto line = [](const char* label, double value, double std_dev) {
    std::cout << label << " = " << std::fixed << std::setprecision(3) << value << " px  (± "
              << std_dev << ")\n";
  };
  line("fx", result.fx, result.fx_std_dev);
  line("fy", result.fy, result.fy_std_dev);
  line("cx", result.cx, result.cx_std_dev);
  line("cy", result.cy, result.cy_std_dev);
  std::cout << std::defaultfloat << std::setprecision(6)
            << "distortion: k1 = " << result.distortion[0] << ", k2 = " << result.distortion[1]
            << ", p1 = " << result.distortion[2] << ", p2 = " << result.distortion[3];
  if (fit_k3) std::cout << ", k3 = " << result.distortion[4];
  std::cout << "\nCOLMAP cameras.txt line:\n" << CameraToColmapLine(result.camera) << "\n";
}

}  // namespace

int RunCalibrate(int argc, char** argv) {
  CLI::App app(
      "Calibrate a camera from photos of a printed chessboard and write camera.json.\n"
      "Photos of other sizes than the calibrated one are skipped (intrinsics are per size).",
      "parallax calibrate");
  std::string images_dir, pattern, output, size;
  double square_size = 1.0;
  bool fit_k3 = false;
  bool sector_based = false;
  int num_threads = -1;
  app.add_option("--images", images_dir, "Folder of chessboard photos")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--pattern", pattern, "Inner corners per row x per column, e.g. 8x6")
      ->required()
      ->check(DimensionsValidator("8x6"));
  app.add_option("--square", square_size,
                 "Side of one square in any unit (scales the board poses, not the intrinsics)")
      ->check(CLI::PositiveNumber);
  app.add_option("--output", output, "camera.json to write")->required();
  app.add_option("--size", size,
                 "Calibrate the images of this size, WxH (default: the most common size)")
      ->check(DimensionsValidator("1280x960"));
  app.add_flag("--k3", fit_k3,
               "Also fit OpenCV's k3; COLMAP's OPENCV model has none, so the pipeline refuses "
               "such a camera.json");
  app.add_flag("--sector-based", sector_based,
               "Find boards with OpenCV's sector-based detector (more robust to blur)");
  app.add_option("--threads", num_threads, "Worker threads (<= 0: all cores)");
  VerbosityFlags flags;
  AddVerbosityFlags(app, &flags);
  return RunCommand(app, argc, argv, flags, [&] {
    CheckerboardCalibrationOptions options;
    ParseDimensions(pattern, &options.pattern_cols, &options.pattern_rows);
    if (!size.empty()) ParseDimensions(size, &options.required_width, &options.required_height);
    options.square_size = square_size;
    options.fit_k3 = fit_k3;
    options.use_sector_based_detector = sector_based;
    options.num_threads = num_threads;

    const CheckerboardCalibrationResult result =
        CalibrateFromCheckerboards(options, ListCalibrationImages(images_dir));
    std::cout << "Calibrating " << pattern << " chessboard (inner corners) photos in " << images_dir
              << "\n";
    PrintImages(result);
    if (!result.success) {
      std::cout.flush();
      std::cerr << "error: calibration failed: " << result.message << std::endl;
      return 1;
    }
    PrintIntrinsics(result, fit_k3);
    const CalibratedCamera calibrated = CalibratedCameraFromResult(result);
    WriteCameraJson(calibrated, std::filesystem::path(output));
    std::cout << "Wrote " << output << " (use it: parallax reconstruct ... --camera " << output
              << ")\n";
    if (fit_k3 && K3ShiftPixels(calibrated) > 0.1) {
      std::cout << "Note: k3 moves pixels by up to " << std::fixed << std::setprecision(2)
                << K3ShiftPixels(calibrated)
                << " px; the pipeline cannot use this camera.json (rerun without --k3).\n";
    }
    return 0;
  });
}

}  // namespace parallax::cli
