#include "parallax/pipeline/camera_setup.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "parallax/calibration/camera_json.h"
#include "parallax/calibration/exif.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

// Parses one number in full; nullopt for trailing garbage, NaN or infinity.
std::optional<double> ParseDouble(const std::string& token) {
  if (token.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

bool SameCamera(const Camera& a, const Camera& b) {
  return a.model_id == b.model_id && a.width == b.width && a.height == b.height &&
         a.params == b.params && a.has_prior_focal_length == b.has_prior_focal_length &&
         a.focal_length_from_exif == b.focal_length_from_exif;
}

}  // namespace

void CameraSetupOptions::Check() const {
  PARALLAX_CHECK_MSG(!(single_camera && camera_per_image),
                     "single_camera and camera_per_image exclude each other");
  PARALLAX_CHECK_GT(default_focal_length_factor, 0.0);
  PARALLAX_CHECK_GE(sensor_width_mm, 0.0);
}

Eigen::Matrix3d ReadCalibrationMatrix(const std::filesystem::path& path) {
  std::string text = ReadFileToString(path);
  for (char& c : text) {
    if (c == ',' || c == ';' || c == '[' || c == ']') c = ' ';
  }
  std::istringstream stream(text);
  std::vector<double> values;
  std::string token;
  while (stream >> token) {
    const std::optional<double> value = ParseDouble(token);
    if (!value) throw InputError(path.string() + ": '" + token + "' is not a number");
    values.push_back(*value);
  }
  if (values.size() != 9) {
    throw InputError(path.string() + ": expected a 3x3 matrix (9 numbers), found " +
                     std::to_string(values.size()) + " numbers");
  }
  Eigen::Matrix3d K = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values.data());
  if (K(2, 2) == 0 || std::abs(K(1, 0)) > 1e-9 * std::abs(K(2, 2)) || K(2, 0) != 0 ||
      K(2, 1) != 0) {
    throw InputError(path.string() +
                     ": not a calibration matrix (expected [fx s cx; 0 fy cy; 0 0 1])");
  }
  K /= K(2, 2);
  if (K(0, 0) <= 0 || K(1, 1) <= 0) {
    throw InputError(path.string() + ": focal lengths must be positive");
  }
  if (std::abs(K(0, 1)) > 1e-6 * K(0, 0)) {
    PARALLAX_LOG(Warning) << path.string() << ": skew " << K(0, 1)
                          << " is ignored (COLMAP's camera models have none)";
  }
  return K;
}

std::vector<double> ParseCameraParams(const std::string& text) {
  std::vector<double> params;
  std::stringstream stream(text);
  std::string token;
  while (std::getline(stream, token, ',')) {
    const std::optional<double> value = ParseDouble(Trim(token));
    if (!value) throw InputError("--camera-params: '" + Trim(token) + "' is not a number");
    params.push_back(*value);
  }
  if (params.empty()) throw InputError("--camera-params: no values in '" + text + "'");
  return params;
}

CameraModelId SelectedCameraModel(const CameraSetupOptions& options, bool intrinsics_known) {
  if (options.camera_model.empty()) {
    return intrinsics_known ? CameraModelId::kPinhole : CameraModelId::kSimpleRadial;
  }
  const CameraModelId model_id = CameraModelIdFromName(options.camera_model);
  if (model_id == CameraModelId::kInvalid) {
    std::string known;
    for (const CameraModelId id : kCameraModelIds)
      known += (known.empty() ? "" : ", ") + CameraModelName(id);
    throw InputError("--camera-model: unknown camera model '" + options.camera_model + "' (" +
                     known + ")");
  }
  return model_id;
}

Camera MakeCamera(const CameraSetupOptions& options, const std::optional<Eigen::Matrix3d>& K,
                  size_t width, size_t height, std::optional<double> exif_focal_length) {
  PARALLAX_CHECK(width > 0 && height > 0);
  const CameraModelId model_id =
      SelectedCameraModel(options, K.has_value() || !options.camera_params.empty());
  Camera camera;
  camera.model_id = model_id;
  camera.width = width;
  camera.height = height;
  if (!options.camera_params.empty()) {
    const int num_params = CameraModelNumParams(model_id);
    if (static_cast<int>(options.camera_params.size()) != num_params) {
      throw InputError("--camera-params: " + std::to_string(options.camera_params.size()) +
                       " values, but " + CameraModelName(model_id) + " takes " +
                       std::to_string(num_params) + " (choose the model with --camera-model)");
    }
    camera.params = options.camera_params;
    camera.has_prior_focal_length = !options.refine_known_intrinsics;
    if (!camera.VerifyParams()) {
      throw InputError("--camera-params: focal lengths must be positive and finite");
    }
    return camera;
  }
  if (K) {
    const double fx = (*K)(0, 0), fy = (*K)(1, 1);
    camera.params = CameraModelInitialParams(model_id, 0.5 * (fx + fy), (*K)(0, 2), (*K)(1, 2));
    const std::vector<int> focal_idxs = CameraModelFocalIdxs(model_id);
    if (focal_idxs.size() == 2) {
      camera.params[focal_idxs[0]] = fx;
      camera.params[focal_idxs[1]] = fy;
    }
    camera.has_prior_focal_length = !options.refine_known_intrinsics;
    return camera;
  }
  // An EXIF focal length is close but rounded (35 mm equivalents are whole millimetres, and
  // cameras crop), so unlike COLMAP, which flags it as a prior and refines it anyway, it is
  // left without the prior flag: here the flag holds a camera fixed in bundle adjustment.
  const double focal_length = exif_focal_length.value_or(
      options.default_focal_length_factor * static_cast<double>(std::max(width, height)));
  camera.params = CameraModelInitialParams(model_id, focal_length, width / 2.0, height / 2.0);
  camera.has_prior_focal_length = false;
  camera.focal_length_from_exif = exif_focal_length.has_value();
  return camera;
}

Camera CalibratedCameraForImage(const CameraSetupOptions& options, const Camera& calibrated,
                                const std::string& image_name, size_t width, size_t height) {
  if (width != calibrated.width || height != calibrated.height) {
    throw InputError(image_name + ": image is " + std::to_string(width) + "x" +
                     std::to_string(height) + " but " + options.camera_json_path.string() +
                     " calibrates " + std::to_string(calibrated.width) + "x" +
                     std::to_string(calibrated.height) + " images");
  }
  Camera camera = calibrated;
  camera.camera_id = kInvalidCameraId;
  camera.has_prior_focal_length = !options.refine_known_intrinsics;
  return camera;
}

ImageCameraInfo ImageCameraInfoFromExif(const ExifData& exif, size_t width, size_t height,
                                        double sensor_width_mm) {
  ImageCameraInfo info;
  info.make = exif.make.value_or("");
  info.model = exif.model.value_or("");
  info.focal_length_px = FocalLengthPixelsFromExif(
      exif, static_cast<int>(width), static_cast<int>(height),
      sensor_width_mm > 0 ? std::optional<double>(sensor_width_mm) : std::nullopt);
  return info;
}

std::optional<ExifData> ReadExifHint(const std::filesystem::path& path) {
  try {
    return ReadExif(path);
  } catch (const InputError& error) {
    PARALLAX_LOG(Debug) << error.what();
    return std::nullopt;
  }
}

ImageCameraInfo ReadImageCameraInfo(const std::filesystem::path& path, size_t width, size_t height,
                                    double sensor_width_mm) {
  const std::optional<ExifData> exif = ReadExifHint(path);
  return exif ? ImageCameraInfoFromExif(*exif, width, height, sensor_width_mm) : ImageCameraInfo{};
}

CameraSetup LoadCameraSetup(const CameraSetupOptions& options) {
  options.Check();
  CameraSetup setup;
  setup.options = options;
  const int num_sources = !options.intrinsics_path.empty() + !options.camera_json_path.empty() +
                          !options.camera_params.empty();
  if (num_sources > 1) {
    throw InputError("--camera, --intrinsics and --camera-params exclude each other");
  }
  if (!options.camera_json_path.empty()) {
    if (!options.camera_model.empty() && options.camera_model != "OPENCV") {
      throw InputError("--camera-model " + options.camera_model + ": " +
                       options.camera_json_path.string() + " holds an OPENCV camera");
    }
    setup.calibrated_camera = ReadCameraJson(options.camera_json_path);
  }
  SelectedCameraModel(options, false);  // Reject an unknown model before any work.
  if (!options.intrinsics_path.empty()) setup.K = ReadCalibrationMatrix(options.intrinsics_path);
  // The number and values of --camera-params do not depend on the image size.
  if (!options.camera_params.empty()) MakeCamera(options, std::nullopt, 640, 480);
  return setup;
}

CameraAssigner::CameraAssigner(CameraSetup setup, Database* database)
    : setup_(std::move(setup)), database_(database) {
  PARALLAX_CHECK(database != nullptr);
}

bool CameraAssigner::UsesExif() const { return !setup_.IntrinsicsKnown() && options_.use_exif; }

camera_t CameraAssigner::CameraForImage(const std::string& image_path, size_t width,
                                        size_t height) {
  ImageCameraInfo info;
  if (UsesExif() && std::filesystem::is_regular_file(image_path)) {
    info = ReadImageCameraInfo(image_path, width, height, options_.sensor_width_mm);
  }
  return CameraForImage(image_path, width, height, info);
}

camera_t CameraAssigner::CameraForImage(const std::string& image_name, size_t width, size_t height,
                                        const ImageCameraInfo& info) {
  const bool intrinsics_known = setup_.IntrinsicsKnown();
  if (info.focal_length_px) {
    PARALLAX_LOG(Debug) << image_name << ": EXIF focal length " << *info.focal_length_px << " px";
  }
  const Camera wanted =
      setup_.calibrated_camera
          ? CalibratedCameraForImage(options_, *setup_.calibrated_camera, image_name, width, height)
          : MakeCamera(options_, setup_.K, width, height,
                       intrinsics_known ? std::nullopt : info.focal_length_px);
  if (options_.camera_per_image) return database_->WriteCamera(wanted);

  if (options_.single_camera && single_camera_id_) {
    if (*single_camera_size_ != std::make_pair(width, height)) {
      throw InputError(image_name + ": image is " + std::to_string(width) + "x" +
                       std::to_string(height) + " but the single camera is " +
                       std::to_string(single_camera_size_->first) + "x" +
                       std::to_string(single_camera_size_->second));
    }
    return *single_camera_id_;
  }
  // Known intrinsics are one camera per size; otherwise the EXIF body and focal length count.
  const CameraKey key = intrinsics_known ? CameraKey{width, height, "", "", 0.0}
                                         : CameraKey{width, height, info.make, info.model,
                                                     info.focal_length_px.value_or(0.0)};
  const auto it = camera_by_key_.find(key);
  if (it != camera_by_key_.end()) return it->second;

  // A camera left by an earlier (interrupted) run with exactly these settings is reused, unless
  // this run gave it to other images already (two bodies with equal guesses stay apart).
  camera_t camera_id = kInvalidCameraId;
  for (const Camera& camera : database_->ReadAllCameras()) {
    const bool claimed =
        std::any_of(camera_by_key_.begin(), camera_by_key_.end(),
                    [&](const auto& entry) { return entry.second == camera.camera_id; });
    if (!claimed && SameCamera(camera, wanted)) {
      camera_id = camera.camera_id;
      break;
    }
  }
  if (camera_id == kInvalidCameraId) camera_id = database_->WriteCamera(wanted);
  camera_by_key_[key] = camera_id;
  if (options_.single_camera) {
    single_camera_id_ = camera_id;
    single_camera_size_ = {width, height};
  }
  return camera_id;
}

}  // namespace parallax
