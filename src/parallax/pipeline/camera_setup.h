#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "parallax/scene/camera.h"
#include "parallax/scene/database.h"

namespace parallax {

// How cameras are assigned to images during feature extraction.
struct CameraSetupOptions {
  // COLMAP model name; empty: SIMPLE_RADIAL, or PINHOLE when K or params are given.
  std::string camera_model;
  // Explicit intrinsics in the model's order (--camera-params); empty: none.
  std::vector<double> camera_params;
  // A 3x3 calibration matrix as text (--intrinsics); empty: none.
  std::filesystem::path intrinsics_path;
  // One camera for all images (all must have the same size).
  bool single_camera = false;
  // One camera per image. Default (neither flag): one camera per image size.
  bool camera_per_image = false;
  // Focal length guess, as a multiple of the longer image side, when intrinsics are unknown.
  double default_focal_length_factor = 1.2;
  void Check() const;
};

// Reads a 3x3 matrix (9 numbers separated by whitespace or commas; Windows line endings and
// trailing spaces are fine). Throws InputError naming the file when it is malformed or not
// an upper-triangular calibration matrix with positive focal lengths.
Eigen::Matrix3d ReadCalibrationMatrix(const std::filesystem::path& path);

// Parses "p1,p2,..." (--camera-params). Throws InputError on a malformed number.
std::vector<double> ParseCameraParams(const std::string& text);

// The camera model the options select: the named one (throws InputError for an unknown
// name), else PINHOLE when the intrinsics are known (K or params), else SIMPLE_RADIAL.
CameraModelId SelectedCameraModel(const CameraSetupOptions& options, bool intrinsics_known);

// A camera (invalid id) for an image of this size: explicit params, else K (principal point
// and focal lengths from K, zero distortion), else focal = factor * max(width, height) at the
// image centre with has_prior_focal_length = false.
Camera MakeCamera(const CameraSetupOptions& options, const std::optional<Eigen::Matrix3d>& K,
                  size_t width, size_t height);

// Assigns cameras to new images, writing them to the database as needed. Reuses matching
// cameras already in the database so a resumed extraction does not duplicate them.
// Not thread-safe (serialise with the database writes).
class CameraAssigner {
 public:
  // Reads K from options.intrinsics_path if set (throws InputError).
  CameraAssigner(const CameraSetupOptions& options, Database* database);
  // The camera id for a new image of this size. Throws InputError naming `image_name` when
  // single_camera is set and the size differs from the camera's.
  camera_t CameraForImage(const std::string& image_name, size_t width, size_t height);

 private:
  CameraSetupOptions options_;
  Database* database_;
  std::optional<Eigen::Matrix3d> K_;
  // Cameras by (width, height) for the per-size and single-camera modes.
  std::map<std::pair<size_t, size_t>, camera_t> camera_by_size_;
  std::optional<camera_t> single_camera_id_;
};

}  // namespace parallax
