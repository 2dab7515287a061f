#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace parallax {

// Camera models with COLMAP's ids, names and parameter orders, so that cameras.txt/bin and
// database blobs are interchangeable with COLMAP.
enum class CameraModelId : int {
  kInvalid = -1,
  kSimplePinhole = 0,  // f, cx, cy
  kPinhole = 1,        // fx, fy, cx, cy
  kSimpleRadial = 2,   // f, cx, cy, k
  kRadial = 3,         // f, cx, cy, k1, k2
  kOpenCV = 4,         // fx, fy, cx, cy, k1, k2, p1, p2
};

// Each model is a struct of constants and templated projection functions (usable with Ceres
// Jets). ImgFromCam projects a point (u, v, w) in camera coordinates to pixels; the distortion
// is applied to normalised coordinates (u/w, v/w).
struct SimplePinholeModel {
  static constexpr CameraModelId kId = CameraModelId::kSimplePinhole;
  static constexpr int kNumParams = 3;
  static constexpr const char* kName = "SIMPLE_PINHOLE";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr int kNumExtraParams = 0;
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    *x = params[0] * u / w + params[1];
    *y = params[0] * v / w + params[2];
  }
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    *du = T(0);
    *dv = T(0);
  }
};

struct PinholeModel {
  static constexpr CameraModelId kId = CameraModelId::kPinhole;
  static constexpr int kNumParams = 4;
  static constexpr const char* kName = "PINHOLE";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr int kNumExtraParams = 0;
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    *x = params[0] * u / w + params[2];
    *y = params[1] * v / w + params[3];
  }
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    *du = T(0);
    *dv = T(0);
  }
};

struct SimpleRadialModel {
  static constexpr CameraModelId kId = CameraModelId::kSimpleRadial;
  static constexpr int kNumParams = 4;
  static constexpr const char* kName = "SIMPLE_RADIAL";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr int kNumExtraParams = 1;
  // Distortion offset (du, dv) added to normalised coordinates (u, v).
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k = params[3];
    const T radial = k * (u * u + v * v);
    *du = u * radial;
    *dv = v * radial;
  }
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    u /= w;
    v /= w;
    T du, dv;
    Distortion(params, u, v, &du, &dv);
    *x = params[0] * (u + du) + params[1];
    *y = params[0] * (v + dv) + params[2];
  }
};

struct RadialModel {
  static constexpr CameraModelId kId = CameraModelId::kRadial;
  static constexpr int kNumParams = 5;
  static constexpr const char* kName = "RADIAL";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr int kNumExtraParams = 2;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T r2 = u * u + v * v;
    const T radial = params[3] * r2 + params[4] * r2 * r2;
    *du = u * radial;
    *dv = v * radial;
  }
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    u /= w;
    v /= w;
    T du, dv;
    Distortion(params, u, v, &du, &dv);
    *x = params[0] * (u + du) + params[1];
    *y = params[0] * (v + dv) + params[2];
  }
};

struct OpenCVModel {
  static constexpr CameraModelId kId = CameraModelId::kOpenCV;
  static constexpr int kNumParams = 8;
  static constexpr const char* kName = "OPENCV";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr int kNumExtraParams = 4;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k1 = params[4], k2 = params[5], p1 = params[6], p2 = params[7];
    const T u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
    const T radial = k1 * r2 + k2 * r2 * r2;
    *du = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2);
    *dv = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2);
  }
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    u /= w;
    v /= w;
    T du, dv;
    Distortion(params, u, v, &du, &dv);
    *x = params[0] * (u + du) + params[2];
    *y = params[1] * (v + dv) + params[3];
  }
};

// Calls visitor.template operator()<Model>() for the model with this id, e.g.
//   VisitCameraModel(id, [&]<typename Model>() { return Model::kNumParams; });
// Throws CheckError for an invalid id.
template <typename Visitor>
decltype(auto) VisitCameraModel(CameraModelId model_id, Visitor&& visitor);

bool ExistsCameraModel(int model_id);
std::string CameraModelName(CameraModelId model_id);
// kInvalid when the name is unknown.
CameraModelId CameraModelIdFromName(const std::string& name);
int CameraModelNumParams(CameraModelId model_id);
std::vector<int> CameraModelFocalIdxs(CameraModelId model_id);
std::vector<int> CameraModelPrincipalPointIdxs(CameraModelId model_id);
std::vector<int> CameraModelExtraIdxs(CameraModelId model_id);
// Parameters for a camera of this model with the given focal length and principal point,
// zero distortion.
std::vector<double> CameraModelInitialParams(CameraModelId model_id, double focal_length,
                                             double principal_point_x, double principal_point_y);
// Pixel coordinates of a point in camera coordinates (w > 0 expected).
Eigen::Vector2d CameraModelImgFromCam(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector3d& point_in_cam);
// Normalised camera coordinates (u, v) with w = 1 of a pixel; inverts the distortion by
// Newton iterations.
Eigen::Vector2d CameraModelCamFromImg(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector2d& xy);

// ---------------------------------------------------------------------------------------------
[[noreturn]] void ThrowInvalidCameraModel(int model_id);

template <typename Visitor>
decltype(auto) VisitCameraModel(CameraModelId model_id, Visitor&& visitor) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole:
      return visitor.template operator()<SimplePinholeModel>();
    case CameraModelId::kPinhole:
      return visitor.template operator()<PinholeModel>();
    case CameraModelId::kSimpleRadial:
      return visitor.template operator()<SimpleRadialModel>();
    case CameraModelId::kRadial:
      return visitor.template operator()<RadialModel>();
    case CameraModelId::kOpenCV:
      return visitor.template operator()<OpenCVModel>();
    default:
      break;
  }
  ThrowInvalidCameraModel(static_cast<int>(model_id));
}

}  // namespace parallax
