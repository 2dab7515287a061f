#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace parallax {

// Camera models with COLMAP's ids, names and parameter orders, so that cameras.txt/bin and
// database blobs are interchangeable with COLMAP.
//
// A model is defined once, by two things:
//   1. a traits struct `<Name>Traits` with what is particular to it: its COLMAP id and name,
//      its parameter names in order (COLMAP's params_info, from which the parameter count
//      is taken), which of them are the focal lengths and the principal point, and, for a
//      model with extra (distortion) parameters, its distortion function: the offset (du, dv)
//      added to normalised coordinates (u, v), templated so that Ceres' Jets go through it;
//   2. a line `X(<Name>)` in PARALLAX_CAMERA_MODELS below, which makes
//      CameraModelId::k<Name>, the type <Name>Model = CameraModel<<Name>Traits>, and the
//      model's case in VisitCameraModel, ExistsCameraModel and the lookups by name and id.
// CameraModel<Traits> writes the rest once for every model: the projection ImgFromCam, its
// inverse CamFromImg (Newton iterations on the distortion), the parameter groups. The
// Jacobians are Ceres' dual numbers through ImgFromCam (estimators/cost_functions).
//
// Projection: a point (u, v, w) in camera coordinates goes to normalised coordinates
// (u/w, v/w), is distorted, then scaled by the focal length(s) and shifted by the principal
// point. COLMAP's pixel convention: the top-left pixel's centre is (0.5, 0.5).

// f, cx, cy. No distortion.
struct SimplePinholeTraits {
  static constexpr int kColmapId = 0;
  static constexpr const char* kName = "SIMPLE_PINHOLE";
  static constexpr const char* kParamsInfo = "f, cx, cy";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
};

// fx, fy, cx, cy. No distortion.
struct PinholeTraits {
  static constexpr int kColmapId = 1;
  static constexpr const char* kName = "PINHOLE";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
};

// One radial coefficient: d(u) = k r^2 u.
struct SimpleRadialTraits {
  static constexpr int kColmapId = 2;
  static constexpr const char* kName = "SIMPLE_RADIAL";
  static constexpr const char* kParamsInfo = "f, cx, cy, k";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k = params[3];
    const T radial = k * (u * u + v * v);
    *du = u * radial;
    *dv = v * radial;
  }
};

// Two radial coefficients: d(u) = (k1 r^2 + k2 r^4) u.
struct RadialTraits {
  static constexpr int kColmapId = 3;
  static constexpr const char* kName = "RADIAL";
  static constexpr const char* kParamsInfo = "f, cx, cy, k1, k2";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T r2 = u * u + v * v;
    const T radial = params[3] * r2 + params[4] * r2 * r2;
    *du = u * radial;
    *dv = v * radial;
  }
};

// OpenCV's model with two radial (k1, k2) and two tangential (p1, p2) coefficients.
struct OpenCVTraits {
  static constexpr int kColmapId = 4;
  static constexpr const char* kName = "OPENCV";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, k1, k2, p1, p2";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k1 = params[4], k2 = params[5], p1 = params[6], p2 = params[7];
    const T u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
    const T radial = k1 * r2 + k2 * r2 * r2;
    *du = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2);
    *dv = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2);
  }
};

// The registry: one line per model, X(Name) for the traits NameTraits above.
#define PARALLAX_CAMERA_MODELS(X) \
  X(SimplePinhole)                \
  X(Pinhole)                      \
  X(SimpleRadial)                 \
  X(Radial)                       \
  X(OpenCV)

// The models' ids: kSimplePinhole = 0, kPinhole = 1, ... from the registry and the traits.
enum class CameraModelId : int {
  kInvalid = -1,
#define PARALLAX_CAMERA_MODEL_ENUMERATOR(Name) k##Name = Name##Traits::kColmapId,
  PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_ENUMERATOR)
#undef PARALLAX_CAMERA_MODEL_ENUMERATOR
};

// The number of comma-separated names in a params_info string.
constexpr int CountParamNames(const char* params_info) {
  int count = 1;
  for (; *params_info != '\0'; ++params_info) count += *params_info == ',';
  return count;
}

// A model from its traits: constants and templated functions (usable with Ceres Jets).
template <typename Traits>
struct CameraModel : Traits {
  static constexpr CameraModelId kId = static_cast<CameraModelId>(Traits::kColmapId);
  static constexpr int kNumParams = CountParamNames(Traits::kParamsInfo);
  static constexpr int kNumExtraParams = kNumParams - static_cast<int>(Traits::kFocalIdxs.size()) -
                                         static_cast<int>(Traits::kPrincipalPointIdxs.size());
  // The parameters that are neither focal lengths nor principal point, in order.
  static constexpr std::array<int, kNumExtraParams> kExtraIdxs = [] {
    std::array<int, kNumExtraParams> idxs{};
    int count = 0;
    for (int i = 0; i < kNumParams; ++i) {
      bool grouped = false;
      for (int idx : Traits::kFocalIdxs) grouped = grouped || idx == i;
      for (int idx : Traits::kPrincipalPointIdxs) grouped = grouped || idx == i;
      if (!grouped && count < kNumExtraParams) idxs[count++] = i;
    }
    return idxs;
  }();

  static_assert(Traits::kFocalIdxs.size() == 1 || Traits::kFocalIdxs.size() == 2);
  static_assert(Traits::kPrincipalPointIdxs.size() == 2);
  static_assert(kNumExtraParams >= 0);
  // A model has a distortion function exactly when it has extra parameters.
  static_assert((kNumExtraParams > 0) == requires(const double* params, double* d) {
    Traits::Distortion(params, 0.0, 0.0, d, d);
  });

  // Pixel coordinates (x, y) of the point (u, v, w) in camera coordinates. Without
  // distortion f u / w + c; with it f (u/w + du) + c (the operations in this order: the
  // models' bits depend on it).
  template <typename T>
  static void ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    const T& fx = params[Traits::kFocalIdxs.front()];
    const T& fy = params[Traits::kFocalIdxs.back()];
    const T& cx = params[Traits::kPrincipalPointIdxs[0]];
    const T& cy = params[Traits::kPrincipalPointIdxs[1]];
    if constexpr (kNumExtraParams == 0) {
      *x = fx * u / w + cx;
      *y = fy * v / w + cy;
    } else {
      u /= w;
      v /= w;
      T du, dv;
      Traits::Distortion(params, u, v, &du, &dv);
      *x = fx * (u + du) + cx;
      *y = fy * (v + dv) + cy;
    }
  }

  // Distortion offset (du, dv) added to normalised coordinates (u, v); zero without extra
  // parameters.
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    if constexpr (kNumExtraParams == 0) {
      *du = T(0);
      *dv = T(0);
    } else {
      Traits::Distortion(params, u, v, du, dv);
    }
  }

  // Normalised camera coordinates (u, v) with w = 1 of the pixel `xy`: the distortion is
  // inverted by Newton iterations. Defined in camera_models.cc for the registered models.
  static Eigen::Vector2d CamFromImg(const double* params, const Eigen::Vector2d& xy);
};

#define PARALLAX_CAMERA_MODEL_TYPE(Name) using Name##Model = CameraModel<Name##Traits>;
PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_TYPE)
#undef PARALLAX_CAMERA_MODEL_TYPE

// Every registered model's id, in registry order.
inline constexpr CameraModelId kCameraModelIds[] = {
#define PARALLAX_CAMERA_MODEL_ID(Name) CameraModelId::k##Name,
    PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_ID)
#undef PARALLAX_CAMERA_MODEL_ID
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
// The parameter names in order, as COLMAP prints them: "f, cx, cy, k".
std::string CameraModelParamsInfo(CameraModelId model_id);
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
#define PARALLAX_CAMERA_MODEL_CASE(Name) \
  case CameraModelId::k##Name:           \
    return visitor.template operator()<Name##Model>();
    PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_CASE)
#undef PARALLAX_CAMERA_MODEL_CASE
    default:
      break;
  }
  ThrowInvalidCameraModel(static_cast<int>(model_id));
}

}  // namespace parallax
