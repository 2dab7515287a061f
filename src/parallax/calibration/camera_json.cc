#include "parallax/calibration/camera_json.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

using Json = nlohmann::json;

constexpr const char* kParamNames[] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};

// Shortest decimal that reads back to the same double.
std::string FormatDouble(double value) {
  char buffer[64];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  PARALLAX_CHECK(error == std::errc());
  return std::string(buffer, end);
}

const Json& RequireField(const Json& root, const char* name, const std::string& source) {
  const auto it = root.find(name);
  if (it == root.end()) throw InputError(source + ": missing field \"" + name + "\"");
  return *it;
}

double RequireFiniteNumber(const Json& root, const char* name, const std::string& source) {
  const Json& value = RequireField(root, name, source);
  if (!value.is_number()) throw InputError(source + ": field \"" + name + "\" is not a number");
  const double number = value.get<double>();
  if (!std::isfinite(number)) throw InputError(source + ": field \"" + name + "\" is not finite");
  return number;
}

int64_t RequireInteger(const Json& root, const char* name, const std::string& source) {
  const double number = RequireFiniteNumber(root, name, source);
  if (number != std::floor(number) || std::abs(number) > 1e15) {
    throw InputError(source + ": field \"" + name + "\" is not an integer");
  }
  return static_cast<int64_t>(number);
}

}  // namespace

std::string CameraToColmapLine(const Camera& camera) {
  const camera_t camera_id = camera.camera_id == kInvalidCameraId ? 1 : camera.camera_id;
  std::ostringstream line;
  line << camera_id << ' ' << camera.ModelName() << ' ' << camera.width << ' ' << camera.height;
  for (double param : camera.params) line << ' ' << FormatDouble(param);
  return line.str();
}

double K3ShiftPixels(const CalibratedCamera& calibrated) {
  const Camera& camera = calibrated.camera;
  double max_shift = 0;
  for (const double x : {0.0, static_cast<double>(camera.width)}) {
    for (const double y : {0.0, static_cast<double>(camera.height)}) {
      const double dx = x - camera.PrincipalPointX();
      const double dy = y - camera.PrincipalPointY();
      const double u = dx / camera.FocalLengthX();
      const double v = dy / camera.FocalLengthY();
      const double r2 = u * u + v * v;
      // k3 r^6 scales the normalised offset, hence the pixel offset from the principal point.
      max_shift = std::max(max_shift, std::abs(calibrated.k3) * r2 * r2 * r2 * std::hypot(dx, dy));
    }
  }
  return max_shift;
}

void WriteCameraJson(const CalibratedCamera& calibrated, std::ostream& stream) {
  const Camera& camera = calibrated.camera;
  PARALLAX_CHECK_MSG(camera.model_id == CameraModelId::kOpenCV,
                     "camera.json holds OPENCV cameras, not " << camera.ModelName());
  PARALLAX_CHECK(camera.VerifyParams());
  // ordered_json keeps the documented field order, so files diff and read well.
  nlohmann::ordered_json root;
  root["model"] = camera.ModelName();
  root["width"] = camera.width;
  root["height"] = camera.height;
  for (size_t i = 0; i < camera.params.size(); ++i) root[kParamNames[i]] = camera.params[i];
  root["k3"] = calibrated.k3;
  root["rms"] = calibrated.rms_error;
  root["num_images"] = calibrated.num_images;
  root["colmap"] = CameraToColmapLine(camera);
  stream << root.dump(2) << "\n";
}

void WriteCameraJson(const CalibratedCamera& calibrated, const std::filesystem::path& path) {
  WriteFileAtomically(path, [&](std::ostream& stream) { WriteCameraJson(calibrated, stream); });
}

CalibratedCamera ParseCameraJson(const std::string& text, const std::string& source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::exception& error) {
    // parse_error, and out_of_range for a number beyond double (1e400).
    throw InputError(source + ": not valid JSON: " + error.what());
  }
  if (!root.is_object()) throw InputError(source + ": expected a JSON object");

  const Json& model = RequireField(root, "model", source);
  if (!model.is_string()) throw InputError(source + ": field \"model\" is not a string");
  if (model.get<std::string>() != "OPENCV") {
    throw InputError(source + ": model \"" + model.get<std::string>() +
                     "\" is not supported (expected \"OPENCV\")");
  }
  CalibratedCamera calibrated;
  Camera& camera = calibrated.camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  const int64_t width = RequireInteger(root, "width", source);
  const int64_t height = RequireInteger(root, "height", source);
  if (width <= 0 || height <= 0) {
    throw InputError(source + ": width and height must be positive (got " + std::to_string(width) +
                     " x " + std::to_string(height) + ")");
  }
  camera.width = static_cast<size_t>(width);
  camera.height = static_cast<size_t>(height);
  for (const char* name : kParamNames) {
    camera.params.push_back(RequireFiniteNumber(root, name, source));
  }
  if (camera.params[0] <= 0 || camera.params[1] <= 0) {
    throw InputError(source + ": focal lengths fx and fy must be positive");
  }
  camera.has_prior_focal_length = true;
  if (root.contains("k3")) calibrated.k3 = RequireFiniteNumber(root, "k3", source);
  if (root.contains("rms")) calibrated.rms_error = RequireFiniteNumber(root, "rms", source);
  if (root.contains("num_images")) {
    calibrated.num_images = static_cast<int>(
        std::clamp<int64_t>(RequireInteger(root, "num_images", source), 0, 1 << 30));
  }
  return calibrated;
}

CalibratedCamera ReadCalibratedCameraJson(const std::filesystem::path& path) {
  return ParseCameraJson(ReadFileToString(path), path.string());
}

Camera ReadCameraJson(const std::filesystem::path& path, double max_k3_shift_px) {
  const CalibratedCamera calibrated = ReadCalibratedCameraJson(path);
  const double shift = K3ShiftPixels(calibrated);
  if (shift > max_k3_shift_px) {
    throw InputError(path.string() + ": k3 = " + FormatDouble(calibrated.k3) +
                     " moves pixels by up to " + FormatDouble(std::round(shift * 100) / 100) +
                     " px, but COLMAP's OPENCV model has no k3; recalibrate without k3 "
                     "(the default of parallax calibrate)");
  }
  return calibrated.camera;
}

}  // namespace parallax
