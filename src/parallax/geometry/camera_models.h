#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace parallax {

// Camera models with COLMAP's ids, names and parameter orders, so that cameras.txt/bin and
// database blobs are interchangeable with COLMAP (checked against a COLMAP 4.2 fixture in
// scene/testdata/colmap42_camera_models).
//
// A model is defined once, by two things:
//   1. a traits struct `<Name>Traits` with what is particular to it: its COLMAP id and name,
//      its parameter names in order (COLMAP's params_info, from which the parameter count
//      is taken), which of them are the focal lengths and the principal point, its
//      projection family (kProjection, perspective when absent), and, for a model with
//      extra (distortion) parameters, its distortion function: the offset (du, dv) added to
//      normalised or fisheye coordinates (u, v), templated so that Ceres' Jets go through
//      it. A model whose projection has a closed form of its own (division, EUCM,
//      equirectangular) gives it as Project/Unproject instead;
//   2. a line `X(<Name>)` in PARALLAX_CAMERA_MODELS below, which makes
//      CameraModelId::k<Name>, the type <Name>Model = CameraModel<<Name>Traits>, and the
//      model's case in VisitCameraModel, ExistsCameraModel and the lookups by name and id.
// CameraModel<Traits> writes the rest once for every model: the projection ImgFromCam, its
// inverses CamFromImg (normalised coordinates) and CamRayFromImg (unit bearing), the
// parameter groups. The Jacobians are Ceres' dual numbers through ImgFromCam
// (estimators/cost_functions).
//
// Projection families:
//   kPerspective: (u, v, w) goes to normalised coordinates (u/w, v/w), is distorted, then
//     scaled by the focal length(s) and shifted by the principal point.
//   kFisheye: the ray's angle theta from the optical axis, atan2(|(u, v)|, w), is the
//     radius of the fisheye coordinates (u, v) theta / |(u, v)| (equidistant), which are
//     distorted, scaled and shifted as above. COLMAP computes theta as atan(|(u, v)| / w)
//     and refuses w <= 0; atan2 gives the same value in front of the camera and keeps
//     lenses wider than 180 degrees (rays behind the image plane) valid.
//   kSpherical: no focal length; the parameters are the image size (EQUIRECTANGULAR).
// COLMAP's pixel convention: the top-left pixel's centre is (0.5, 0.5).

enum class CameraProjection { kPerspective, kFisheye, kSpherical };

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

// OpenCV's fisheye model (cv::fisheye): equidistant with theta (1 + k1 theta^2 + k2 theta^4
// + k3 theta^6 + k4 theta^8).
struct OpenCVFisheyeTraits {
  static constexpr int kColmapId = 5;
  static constexpr const char* kName = "OPENCV_FISHEYE";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, k1, k2, k3, k4";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T theta2 = u * u + v * v;
    const T theta4 = theta2 * theta2;
    const T radial = params[4] * theta2 + params[5] * theta4 + params[6] * theta4 * theta2 +
                     params[7] * theta4 * theta4;
    *du = u * radial;
    *dv = v * radial;
  }
};

// OpenCV's full model: rational radial (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4
// + k6 r^6) and tangential p1, p2.
struct FullOpenCVTraits {
  static constexpr int kColmapId = 6;
  static constexpr const char* kName = "FULL_OPENCV";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k1 = params[4], k2 = params[5], p1 = params[6], p2 = params[7];
    const T k3 = params[8], k4 = params[9], k5 = params[10], k6 = params[11];
    const T u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
    const T r4 = r2 * r2, r6 = r4 * r2;
    const T radial = (T(1) + k1 * r2 + k2 * r4 + k3 * r6) / (T(1) + k4 * r2 + k5 * r4 + k6 * r6);
    *du = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2) - u;
    *dv = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2) - v;
  }
};

// Devernay and Faugeras' field-of-view model: radius r goes to atan(2 r tan(omega / 2)) /
// omega. Near omega = 0 or r = 0 the factor's Taylor series (COLMAP's branches), so that
// the Jacobian stays finite there.
struct FOVTraits {
  static constexpr int kColmapId = 7;
  static constexpr const char* kName = "FOV";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, omega";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  // At omega = 0 the factor's derivative in omega is zero: refinement could never leave it.
  static constexpr std::array<double, 1> kInitialExtraParams = {1e-2};
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    using std::atan;
    using std::sqrt;
    using std::tan;
    const T omega = params[4];
    const T radius2 = u * u + v * v;
    const T omega2 = omega * omega;
    constexpr double kEpsilon = 1e-4;
    T factor;
    if (omega2 < T(kEpsilon)) {
      factor = (omega2 * radius2) / T(3) - omega2 / T(12) + T(1);
    } else if (radius2 < T(kEpsilon)) {
      const T tan_half_omega = tan(omega / T(2));
      factor =
          (T(-2) * tan_half_omega * (T(4) * radius2 * tan_half_omega * tan_half_omega - T(3))) /
          (T(3) * omega);
    } else {
      const T radius = sqrt(radius2);
      factor = atan(radius * T(2) * tan(omega / T(2))) / (radius * omega);
    }
    *du = u * (factor - T(1));
    *dv = v * (factor - T(1));
  }
};

// OPENCV_FISHEYE with one radial coefficient and one focal length.
struct SimpleRadialFisheyeTraits {
  static constexpr int kColmapId = 8;
  static constexpr const char* kName = "SIMPLE_RADIAL_FISHEYE";
  static constexpr const char* kParamsInfo = "f, cx, cy, k";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T radial = params[3] * (u * u + v * v);
    *du = u * radial;
    *dv = v * radial;
  }
};

// OPENCV_FISHEYE with two radial coefficients and one focal length.
struct RadialFisheyeTraits {
  static constexpr int kColmapId = 9;
  static constexpr const char* kName = "RADIAL_FISHEYE";
  static constexpr const char* kParamsInfo = "f, cx, cy, k1, k2";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T theta2 = u * u + v * v;
    const T radial = params[3] * theta2 + params[4] * theta2 * theta2;
    *du = u * radial;
    *dv = v * radial;
  }
};

// Weng et al.'s thin-prism model on fisheye coordinates: radial k1..k4, tangential p1, p2,
// thin prism sx1, sy1.
struct ThinPrismFisheyeTraits {
  static constexpr int kColmapId = 10;
  static constexpr const char* kName = "THIN_PRISM_FISHEYE";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T k1 = params[4], k2 = params[5], p1 = params[6], p2 = params[7];
    const T k3 = params[8], k4 = params[9], sx1 = params[10], sy1 = params[11];
    const T u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
    const T r4 = r2 * r2, r6 = r4 * r2, r8 = r4 * r4;
    const T radial = k1 * r2 + k2 * r4 + k3 * r6 + k4 * r8;
    *du = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2) + sx1 * r2;
    *dv = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2) + sy1 * r2;
  }
};

// Project Aria's Fisheye624: radial k0..k5 in theta^2..theta^12, then tangential p0, p1 and
// thin prism s0..s3 on the radially distorted coordinates.
struct RadTanThinPrismFisheyeTraits {
  static constexpr int kColmapId = 11;
  static constexpr const char* kName = "RAD_TAN_THIN_PRISM_FISHEYE";
  static constexpr const char* kParamsInfo =
      "fx, fy, cx, cy, k0, k1, k2, k3, k4, k5, p0, p1, s0, s1, s2, s3";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    const T theta2 = u * u + v * v;
    T radial = T(1);
    T theta_power = T(1);
    for (int i = 0; i < 6; ++i) {
      theta_power *= theta2;
      radial += params[4 + i] * theta_power;
    }
    const T p0 = params[10], p1 = params[11];
    const T s0 = params[12], s1 = params[13], s2 = params[14], s3 = params[15];
    const T x = radial * u, y = radial * v;
    const T x2 = x * x, y2 = y * y, xy = x * y, r2 = x2 + y2, r4 = r2 * r2;
    const T distorted_x = x + T(2) * p1 * xy + p0 * (r2 + T(2) * x2) + s0 * r2 + s1 * r4;
    const T distorted_y = y + T(2) * p0 * xy + p1 * (r2 + T(2) * y2) + s2 * r2 + s3 * r4;
    *du = distorted_x - u;
    *dv = distorted_y - v;
  }
};

// Fitzgibbon's one-parameter division model: the ray of distorted normalised coordinates
// (x, y) is (x, y, 1 + k (x^2 + y^2)). Closed-form both ways; with k < 0 it reaches beyond
// 180 degrees.
template <typename T>
bool DivisionProject(T fx, T fy, T cx, T cy, T k, T u, T v, T w, T* x, T* y) {
  using std::sqrt;
  // (x, y) = s (u, v) with s |(u, v)|^2 k s^2 - w s + 1 = 0, the root that is 1/w at k = 0.
  const T rho2 = u * u + v * v;
  const T discriminant = w * w - T(4) * rho2 * k;
  const bool valid = discriminant >= T(0);
  const T scale = T(2) / (w + sqrt(valid ? discriminant : T(0)));
  *x = fx * scale * u + cx;
  *y = fy * scale * v + cy;
  return valid;
}

// The ray of a pixel under the division model: normalised distorted coordinates (x, y) and
// (x, y, 1 + k (x^2 + y^2)), unit length.
inline Eigen::Vector3d DivisionUnproject(double fx, double fy, double cx, double cy, double k,
                                         const Eigen::Vector2d& xy) {
  const Eigen::Vector2d distorted((xy.x() - cx) / fx, (xy.y() - cy) / fy);
  return Eigen::Vector3d(distorted.x(), distorted.y(), 1.0 + k * distorted.squaredNorm())
      .normalized();
}

struct SimpleDivisionTraits {
  static constexpr int kColmapId = 12;
  static constexpr const char* kName = "SIMPLE_DIVISION";
  static constexpr const char* kParamsInfo = "f, cx, cy, k";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  template <typename T>
  static bool Project(const T* params, T u, T v, T w, T* x, T* y) {
    return DivisionProject(params[0], params[0], params[1], params[2], params[3], u, v, w, x, y);
  }
  static Eigen::Vector3d Unproject(const double* params, const Eigen::Vector2d& xy) {
    return DivisionUnproject(params[0], params[0], params[1], params[2], params[3], xy);
  }
};

struct DivisionTraits {
  static constexpr int kColmapId = 13;
  static constexpr const char* kName = "DIVISION";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, k";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  template <typename T>
  static bool Project(const T* params, T u, T v, T w, T* x, T* y) {
    return DivisionProject(params[0], params[1], params[2], params[3], params[4], u, v, w, x, y);
  }
  static Eigen::Vector3d Unproject(const double* params, const Eigen::Vector2d& xy) {
    return DivisionUnproject(params[0], params[1], params[2], params[3], params[4], xy);
  }
};

// Equidistant fisheye without distortion: the pixel radius is f theta.
struct SimpleFisheyeTraits {
  static constexpr int kColmapId = 14;
  static constexpr const char* kName = "SIMPLE_FISHEYE";
  static constexpr const char* kParamsInfo = "f, cx, cy";
  static constexpr std::array<int, 1> kFocalIdxs = {0};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {1, 2};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
};

struct FisheyeTraits {
  static constexpr int kColmapId = 15;
  static constexpr const char* kName = "FISHEYE";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr CameraProjection kProjection = CameraProjection::kFisheye;
};

// Khomutenko et al.'s enhanced unified camera model: (u, v) / (alpha d + (1 - alpha) w) with
// d = sqrt(beta (u^2 + v^2) + w^2). alpha = 0 is a pinhole; fields of view beyond 180
// degrees for alpha > 0.5.
struct EUCMTraits {
  static constexpr int kColmapId = 16;
  static constexpr const char* kName = "EUCM";
  static constexpr const char* kParamsInfo = "fx, fy, cx, cy, alpha, beta";
  static constexpr std::array<int, 2> kFocalIdxs = {0, 1};
  static constexpr std::array<int, 2> kPrincipalPointIdxs = {2, 3};
  static constexpr std::array<double, 2> kInitialExtraParams = {0.0, 1.0};
  template <typename T>
  static bool Project(const T* params, T u, T v, T w, T* x, T* y) {
    using std::sqrt;
    const T alpha = params[4], beta = params[5];
    const T d2 = beta * (u * u + v * v) + w * w;
    const T d = sqrt(d2 > T(0) ? d2 : T(0));
    const T denominator = alpha * d + (T(1) - alpha) * w;
    *x = params[0] * u / denominator + params[2];
    *y = params[1] * v / denominator + params[3];
    return d2 > T(0) && denominator > T(0);
  }
  static Eigen::Vector3d Unproject(const double* params, const Eigen::Vector2d& xy) {
    const double alpha = params[4], beta = params[5];
    const Eigen::Vector2d m((xy.x() - params[2]) / params[0], (xy.y() - params[3]) / params[1]);
    const double r2 = m.squaredNorm();
    const double radicand = std::max(0.0, 1.0 - (2.0 * alpha - 1.0) * beta * r2);
    const double z =
        (1.0 - alpha * alpha * beta * r2) / (alpha * std::sqrt(radicand) + 1.0 - alpha);
    return Eigen::Vector3d(m.x(), m.y(), z).normalized();
  }
};

// The full sphere onto a 2:1 image: azimuth atan2(u, w) across the width (the optical axis
// at the centre, +x to the right), elevation atan2(-v, |(u, w)|) down the height (+y, the
// camera's down, to the bottom). The parameters are the image's width and height.
struct EquirectangularTraits {
  static constexpr int kColmapId = 17;
  static constexpr const char* kName = "EQUIRECTANGULAR";
  static constexpr const char* kParamsInfo = "w, h";
  static constexpr std::array<int, 0> kFocalIdxs = {};
  static constexpr std::array<int, 0> kPrincipalPointIdxs = {};
  static constexpr CameraProjection kProjection = CameraProjection::kSpherical;
  template <typename T>
  static bool Project(const T* params, T u, T v, T w, T* x, T* y) {
    using std::atan2;
    using std::sqrt;
    const T horizontal = sqrt(u * u + w * w);
    const T azimuth = atan2(u, w);
    const T elevation = atan2(-v, horizontal);
    *x = (azimuth / T(2.0 * M_PI) + T(0.5)) * params[0];
    *y = (T(0.5) - elevation / T(M_PI)) * params[1];
    return horizontal > T(0) || v != T(0);
  }
  static Eigen::Vector3d Unproject(const double* params, const Eigen::Vector2d& xy) {
    const double azimuth = 2.0 * M_PI * (xy.x() / params[0] - 0.5);
    const double elevation = M_PI * (0.5 - xy.y() / params[1]);
    return Eigen::Vector3d(std::cos(elevation) * std::sin(azimuth), -std::sin(elevation),
                           std::cos(elevation) * std::cos(azimuth));
  }
};

// The registry: one line per model, X(Name) for the traits NameTraits above.
#define PARALLAX_CAMERA_MODELS(X) \
  X(SimplePinhole)                \
  X(Pinhole)                      \
  X(SimpleRadial)                 \
  X(Radial)                       \
  X(OpenCV)                       \
  X(OpenCVFisheye)                \
  X(FullOpenCV)                   \
  X(FOV)                          \
  X(SimpleRadialFisheye)          \
  X(RadialFisheye)                \
  X(ThinPrismFisheye)             \
  X(RadTanThinPrismFisheye)       \
  X(SimpleDivision)               \
  X(Division)                     \
  X(SimpleFisheye)                \
  X(Fisheye)                      \
  X(EUCM)                         \
  X(Equirectangular)

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
  static constexpr CameraProjection kProjection = [] {
    if constexpr (requires { Traits::kProjection; }) {
      return Traits::kProjection;
    } else {
      return CameraProjection::kPerspective;
    }
  }();
  // A projection of its own (Project/Unproject) instead of the family's formula.
  static constexpr bool kHasClosedForm = requires(const double* params, double* x) {
    Traits::Project(params, 0.0, 0.0, 1.0, x, x);
  };
  static constexpr int kNumParams = CountParamNames(Traits::kParamsInfo);
  // A spherical model's parameters are all metadata (the image size): never refined.
  static constexpr int kNumMetadataParams =
      kProjection == CameraProjection::kSpherical ? kNumParams : 0;
  static constexpr int kNumExtraParams = kNumParams - static_cast<int>(Traits::kFocalIdxs.size()) -
                                         static_cast<int>(Traits::kPrincipalPointIdxs.size()) -
                                         kNumMetadataParams;
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
  // The extra parameters a new camera starts from: zero unless the traits say otherwise.
  static constexpr std::array<double, kNumExtraParams> kInitialExtraParams = [] {
    if constexpr (requires { Traits::kInitialExtraParams; }) {
      return Traits::kInitialExtraParams;
    } else {
      return std::array<double, kNumExtraParams>{};
    }
  }();

  static_assert(kProjection == CameraProjection::kSpherical
                    ? Traits::kFocalIdxs.empty() && Traits::kPrincipalPointIdxs.empty()
                    : (Traits::kFocalIdxs.size() == 1 || Traits::kFocalIdxs.size() == 2) &&
                          Traits::kPrincipalPointIdxs.size() == 2);
  static_assert(kNumExtraParams >= 0);
  static_assert(kProjection != CameraProjection::kSpherical || kHasClosedForm);
  // A model has a distortion function exactly when it has extra parameters, unless its
  // projection has a closed form of its own.
  static_assert(kHasClosedForm ||
                (kNumExtraParams > 0) == requires(const double* params, double* d) {
                  Traits::Distortion(params, 0.0, 0.0, d, d);
                });

  // Pixel coordinates (x, y) of the point (u, v, w) in camera coordinates. False where the
  // model cannot project it (behind a perspective camera, outside a division model's or
  // EUCM's domain); x and y are then finite but meaningless. Perspective without
  // distortion: f u / w + c; with it f (u/w + du) + c (the operations in this order: the
  // models' bits depend on it).
  template <typename T>
  static bool ImgFromCam(const T* params, T u, T v, T w, T* x, T* y) {
    if constexpr (kHasClosedForm) {
      return Traits::Project(params, u, v, w, x, y);
    } else {
      const T& fx = params[Traits::kFocalIdxs.front()];
      const T& fy = params[Traits::kFocalIdxs.back()];
      const T& cx = params[Traits::kPrincipalPointIdxs[0]];
      const T& cy = params[Traits::kPrincipalPointIdxs[1]];
      bool valid = true;
      if constexpr (kProjection == CameraProjection::kPerspective) {
        valid = w > T(0);
        if constexpr (kNumExtraParams == 0) {
          *x = fx * u / w + cx;
          *y = fy * v / w + cy;
          return valid;
        }
        u /= w;
        v /= w;
      } else {
        using std::atan2;
        using std::sqrt;
        // Equidistant: (u, v) theta / r. Near the axis theta / r = 1 / w to second order,
        // which keeps the Jacobian finite where r's is not.
        const T r2 = u * u + v * v;
        if (r2 > T(1e-24) * w * w) {
          const T r = sqrt(r2);
          const T scale = atan2(r, w) / r;
          u *= scale;
          v *= scale;
        } else {
          valid = w > T(0);
          u /= w;
          v /= w;
        }
      }
      if constexpr (kNumExtraParams > 0) {
        T du, dv;
        Traits::Distortion(params, u, v, &du, &dv);
        *x = fx * (u + du) + cx;
        *y = fy * (v + dv) + cy;
      } else {
        *x = fx * u + cx;
        *y = fy * v + cy;
      }
      return valid;
    }
  }

  // Distortion offset (du, dv) added to normalised (or fisheye) coordinates (u, v); zero
  // without a distortion function.
  template <typename T>
  static void Distortion(const T* params, T u, T v, T* du, T* dv) {
    if constexpr (requires { Traits::Distortion(params, u, v, du, dv); }) {
      Traits::Distortion(params, u, v, du, dv);
    } else {
      *du = T(0);
      *dv = T(0);
    }
  }

  // The unit ray (bearing) in camera coordinates of the pixel `xy`, valid for every pixel
  // the model maps, in front of the camera or behind it. The distortion is inverted by
  // damped Newton iterations. Defined in camera_models.cc for the registered models.
  static Eigen::Vector3d CamRayFromImg(const double* params, const Eigen::Vector2d& xy);
  // Normalised camera coordinates (u, v) with w = 1 of the pixel `xy`: CamRayFromImg
  // divided by its w, meaningful for rays in front of the camera.
  static Eigen::Vector2d CamFromImg(const double* params, const Eigen::Vector2d& xy);
  // A threshold in pixels as an angle (radians) or a distance in normalised coordinates
  // (their scale near the optical axis): divided by the mean focal length, or by the
  // pixels per radian of a spherical image's equator.
  static double CamFromImgThreshold(const double* params, double threshold);
};

#define PARALLAX_CAMERA_MODEL_TYPE(Name) using Name##Model = CameraModel<Name##Traits>;
PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_TYPE)
#undef PARALLAX_CAMERA_MODEL_TYPE

// The most parameters a registered model has (RAD_TAN_THIN_PRISM_FISHEYE's 16): what a
// fixed-size buffer of one camera's parameters or Jacobian columns must hold.
inline constexpr int kMaxCameraModelNumParams = [] {
  int most = 0;
#define PARALLAX_CAMERA_MODEL_MAX(Name) most = std::max(most, Name##Model::kNumParams);
  PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_MAX)
#undef PARALLAX_CAMERA_MODEL_MAX
  return most;
}();

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
CameraProjection CameraModelProjection(CameraModelId model_id);
// SIMPLE_PINHOLE or PINHOLE: what a K matrix describes exactly.
constexpr bool IsPinholeCameraModel(CameraModelId model_id) {
  return model_id == CameraModelId::kSimplePinhole || model_id == CameraModelId::kPinhole;
}
// Parameters for a camera of this model with the given focal length and principal point
// and the model's initial distortion (zero but for FOV and EUCM, whose refinement cannot
// start from zero). A spherical model's parameters are the image size, twice the principal
// point: the focal length is ignored.
std::vector<double> CameraModelInitialParams(CameraModelId model_id, double focal_length,
                                             double principal_point_x, double principal_point_y);
// Pixel coordinates of a point in camera coordinates (for a perspective model w > 0
// expected; fisheye and spherical models project every direction).
Eigen::Vector2d CameraModelImgFromCam(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector3d& point_in_cam);
// Whether the model maps this point in camera coordinates to a pixel (e.g. w > 0 for a
// perspective model); the pixel is then in `xy`. It may still lie outside the image.
bool CameraModelProjects(CameraModelId model_id, const std::vector<double>& params,
                         const Eigen::Vector3d& point_in_cam, Eigen::Vector2d* xy);
// Normalised camera coordinates (u, v) with w = 1 of a pixel, for rays in front of the
// camera; inverts the distortion by Newton iterations.
Eigen::Vector2d CameraModelCamFromImg(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector2d& xy);
// The unit ray of a pixel in camera coordinates, also for rays behind the image plane of
// fisheye, division, EUCM and spherical models.
Eigen::Vector3d CameraModelCamRayFromImg(CameraModelId model_id, const std::vector<double>& params,
                                         const Eigen::Vector2d& xy);
// A pixel threshold in normalised units (radians near the optical axis).
double CameraModelCamFromImgThreshold(CameraModelId model_id, const std::vector<double>& params,
                                      double threshold);

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
