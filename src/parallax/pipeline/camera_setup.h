#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "parallax/calibration/exif.h"
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
  // A camera.json from `parallax calibrate` (--camera): OPENCV model with distortion; empty: none.
  std::filesystem::path camera_json_path;
  // Known intrinsics (--camera, --intrinsics, --camera-params) are only initial values that
  // bundle adjustment refines (--refine-camera): has_prior_focal_length = false.
  bool refine_known_intrinsics = false;
  // Take the initial focal length from the image's EXIF when intrinsics are unknown.
  bool use_exif = true;
  // Sensor width in mm, for EXIF FocalLength without FocalPlaneXResolution; 0: unknown.
  double sensor_width_mm = 0;
  // One camera for all images (all must have the same size).
  bool single_camera = false;
  // One camera per image. Default (neither flag): one per image size and EXIF camera.
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
// and focal lengths from K, zero distortion), else `exif_focal_length` (pixels) or, without
// it, factor * max(width, height) at the image centre. Known intrinsics (params, K) get
// has_prior_focal_length unless refine_known_intrinsics; a guessed or EXIF focal length never
// does, since the mapper holds cameras with a prior fixed (docs/cameras.md).
Camera MakeCamera(const CameraSetupOptions& options, const std::optional<Eigen::Matrix3d>& K,
                  size_t width, size_t height,
                  std::optional<double> exif_focal_length = std::nullopt);

// The camera of a camera.json file for an image of this size, has_prior_focal_length unless
// refine_known_intrinsics. Throws InputError naming `image_name` when the size differs from
// the calibrated one (intrinsics belong to one image size).
Camera CalibratedCameraForImage(const CameraSetupOptions& options, const Camera& calibrated,
                                const std::string& image_name, size_t width, size_t height);

// What tells cameras apart when intrinsics are unknown: the EXIF body and its focal length.
struct ImageCameraInfo {
  std::string make;                       // EXIF Make, empty when absent.
  std::string model;                      // EXIF Model, empty when absent.
  std::optional<double> focal_length_px;  // From EXIF (FocalLengthPixelsFromExif).
};

// The camera information in an image's EXIF block.
ImageCameraInfo ImageCameraInfoFromExif(const ExifData& exif, size_t width, size_t height,
                                        double sensor_width_mm = 0);

// Reads the EXIF of an image file (JPEG; other formats have none here). A file that cannot be
// read or parsed gives no block: the image was decoded already, EXIF is only a hint.
std::optional<ExifData> ReadExifHint(const std::filesystem::path& path);

// ImageCameraInfoFromExif of ReadExifHint (an empty record without EXIF).
ImageCameraInfo ReadImageCameraInfo(const std::filesystem::path& path, size_t width, size_t height,
                                    double sensor_width_mm = 0);

// Assigns cameras to new images, writing them to the database as needed. By default images
// share a camera when they have the same size and, when intrinsics are unknown, the same EXIF
// make, model and focal length. Reuses matching cameras already in the database so a resumed
// extraction does not duplicate them. Not thread-safe (serialise with the database writes).
// What the camera options say before any image is read: the known intrinsics (K.txt,
// camera.json or --camera-params), read and validated. The run's first step; extraction
// assigns cameras from it.
struct CameraSetup {
  CameraSetupOptions options;
  std::optional<Eigen::Matrix3d> K;         // From options.intrinsics_path.
  std::optional<Camera> calibrated_camera;  // From options.camera_json_path.
  // Whether the intrinsics are given (then EXIF is not read).
  bool IntrinsicsKnown() const { return K || calibrated_camera || !options.camera_params.empty(); }
};

// Reads K.txt or camera.json and checks the options against each other and against the
// camera model: two intrinsics sources at once, an unknown model, an unreadable or malformed
// file, or a wrong number of --camera-params is an InputError naming the file or flag.
CameraSetup LoadCameraSetup(const CameraSetupOptions& options);

class CameraAssigner {
 public:
  CameraAssigner(CameraSetup setup, Database* database);
  // The camera id for a new image of this size; `image_path` is read for EXIF when intrinsics
  // are unknown and options.use_exif (a missing file is no EXIF). Throws InputError naming
  // `image_path` when single_camera is set and the size differs from the camera's, or when
  // the size differs from a camera.json's.
  camera_t CameraForImage(const std::string& image_path, size_t width, size_t height);
  // As above with the EXIF information given (nothing is read); callers pass an empty
  // record unless UsesExif().
  camera_t CameraForImage(const std::string& image_name, size_t width, size_t height,
                          const ImageCameraInfo& info);
  // Whether images' EXIF tells their cameras: intrinsics unknown and options.use_exif.
  bool UsesExif() const;

 private:
  // Images with equal keys share a camera.
  using CameraKey = std::tuple<size_t, size_t, std::string, std::string, double>;

  const CameraSetup setup_;
  const CameraSetupOptions& options_ = setup_.options;
  Database* database_;
  std::map<CameraKey, camera_t> camera_by_key_;
  std::optional<std::pair<size_t, size_t>> single_camera_size_;
  std::optional<camera_t> single_camera_id_;
};

}  // namespace parallax
