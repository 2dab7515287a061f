#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "parallax/calibration/camera_json.h"
#include "parallax/scene/camera.h"

namespace parallax {

// Intrinsic calibration from photos of a planar chessboard (Zhang, "A flexible new technique
// for camera calibration", PAMI 2000, as implemented by OpenCV's calibrateCamera).
struct CheckerboardCalibrationOptions {
  // Inner corners per row (cols) and per column (rows) of the board, e.g. 8 x 6.
  int pattern_cols = 8;
  int pattern_rows = 6;
  // Side of one square in any unit; it scales the board poses only, never the intrinsics.
  double square_size = 1.0;
  // Calibrate images of exactly this size; 0 x 0 picks the size shared by the most images.
  int required_width = 0;
  int required_height = 0;
  // Fit OpenCV's sixth-order radial term k3. Off by default because COLMAP's OPENCV model
  // (k1, k2, p1, p2) has none, so a camera fitted with k3 cannot be used by the pipeline.
  bool fit_k3 = false;
  // Largest half-size of cornerSubPix's search window in pixels (the window is 2r+1 wide); it
  // is shrunk on boards whose squares are too small for it, so it never spans two corners.
  int subpixel_window_radius = 11;
  // Find the board with the sector-based detector (findChessboardCornersSB, more robust to
  // blur and distortion) instead of findChessboardCorners; cornerSubPix refines either.
  bool use_sector_based_detector = false;
  // Detect on a copy downscaled to at most this many pixels on its longer side (detection
  // slows down sharply with image size), then refine at full resolution. 0: never downscale.
  int detection_max_image_size = 2000;
  // Fewer boards found than this is a failure (the intrinsics would be poorly constrained).
  int min_num_images = 3;
  // Images are decoded and searched in parallel; <= 0 uses all cores.
  int num_threads = -1;
  void Check() const;
};

enum class CheckerboardImageStatus {
  kUsed,           // Board found; the image is part of the calibration.
  kBoardNotFound,  // Right size, but no complete board was detected.
  kWrongSize,      // Decoded, but its size differs from the calibrated one.
  kUnreadable,     // Could not be decoded as an image.
};
std::string CheckerboardImageStatusName(CheckerboardImageStatus status);

struct CheckerboardImageResult {
  std::filesystem::path path;
  CheckerboardImageStatus status = CheckerboardImageStatus::kUnreadable;
  // Why the image was not used (empty when used).
  std::string reason;
  // Decoded size (0 x 0 when unreadable).
  int width = 0;
  int height = 0;
  // Detected inner corners, row by row (pattern_cols per row); empty unless the board was found.
  std::vector<Eigen::Vector2d> corners;
  // Root-mean-square reprojection error of this image's corners in pixels (used images only).
  double rms_error = 0;
};

struct CheckerboardCalibrationResult {
  // False when fewer than min_num_images boards were found; `message` says why.
  bool success = false;
  std::string message;
  // One entry per input path, in input order.
  std::vector<CheckerboardImageResult> images;
  // Size of the calibrated images.
  int width = 0;
  int height = 0;
  int num_used_images = 0;
  // Root-mean-square reprojection error over all used corners in pixels.
  double rms_error = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // Standard deviations of fx, fy, cx, cy estimated by calibrateCamera (pixels).
  double fx_std_dev = 0, fy_std_dev = 0, cx_std_dev = 0, cy_std_dev = 0;
  // OpenCV order k1, k2, p1, p2, k3 (k3 = 0 unless fit_k3).
  std::vector<double> distortion;
  // OPENCV model (fx, fy, cx, cy, k1, k2, p1, p2), camera_id 1, has_prior_focal_length set.
  // k3 has no place in it: check distortion[4] when fit_k3 was on.
  Camera camera;
};

// Detects the board's inner corners in an 8-bit gray image and refines them to sub-pixel
// accuracy. Nullopt when no complete board is found.
std::optional<std::vector<Eigen::Vector2d>> DetectCheckerboardCorners(
    const CheckerboardCalibrationOptions& options, const cv::Mat& gray);

// Calibrates from corners already detected (one vector per view, row-major pattern order).
// Fills the intrinsic fields of the result (width, height, rms, fx..cy, distortion, camera)
// and per-view RMS errors; `images` is left empty. Fails when there are fewer than
// min_num_images views.
CheckerboardCalibrationResult CalibrateFromCheckerboardCorners(
    const CheckerboardCalibrationOptions& options, int width, int height,
    const std::vector<std::vector<Eigen::Vector2d>>& corners_per_view,
    std::vector<double>* per_view_rms_errors = nullptr);

// Decodes every image, groups them by size (intrinsics are per image size), detects the board
// in the chosen group (required size, else the largest group; ties go to the larger size)
// and calibrates. Unreadable files and other sizes are reported in `images`, not fatal.
// Images are read as an ordinary viewer would, with EXIF orientation applied.
CheckerboardCalibrationResult CalibrateFromCheckerboards(
    const CheckerboardCalibrationOptions& options,
    const std::vector<std::filesystem::path>& image_paths);

// The photos of a calibration folder: files named .jpg, .jpeg, .png, .tif, .tiff or .bmp (any
// case; decoding tells the rest), sorted by name. Throws MissingFileError when the folder does
// not exist and InputError when it holds no such file, each naming the folder.
std::vector<std::filesystem::path> ListCalibrationImages(const std::filesystem::path& dir);

// The result as a camera.json record.
CalibratedCamera CalibratedCameraFromResult(const CheckerboardCalibrationResult& result);

}  // namespace parallax
