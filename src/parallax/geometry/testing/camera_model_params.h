#pragma once

#include <cmath>
#include <vector>

#include "parallax/geometry/camera_models.h"
#include "parallax/util/check.h"

namespace parallax {

// Intrinsics for a 640x480 camera of each model (2048x1024 for the sphere) with distortion
// large enough to matter and small enough that the projection stays one-to-one over
// TestHalfFieldOfView: what the camera-model tests sample.
inline std::vector<double> TestCameraParams(CameraModelId model_id) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole:
      return {800, 320, 240};
    case CameraModelId::kPinhole:
      return {800, 790, 320, 240};
    case CameraModelId::kSimpleRadial:
      return {800, 320, 240, -0.08};
    case CameraModelId::kRadial:
      return {800, 320, 240, -0.08, 0.01};
    case CameraModelId::kOpenCV:
      return {800, 790, 320, 240, -0.08, 0.01, 0.001, -0.002};
    case CameraModelId::kOpenCVFisheye:
      return {300, 305, 320, 240, 0.02, -0.005, 0.001, -0.0002};
    case CameraModelId::kFullOpenCV:
      return {800, 790, 320, 240, -0.08, 0.01, 0.001, -0.002, 0.001, 0.02, -0.01, 0.002};
    case CameraModelId::kFOV:
      return {500, 505, 320, 240, 0.9};
    case CameraModelId::kSimpleRadialFisheye:
      return {300, 320, 240, 0.02};
    case CameraModelId::kRadialFisheye:
      return {300, 320, 240, 0.02, -0.005};
    case CameraModelId::kThinPrismFisheye:
      return {300, 305, 320, 240, 0.02, -0.005, 0.001, -0.002, 0.001, -0.0002, 0.0005, -0.0005};
    case CameraModelId::kRadTanThinPrismFisheye:
      return {300,  305,   320,   240,    0.02,   -0.005,  0.001, -0.0002,
              5e-5, -1e-5, 0.001, -0.002, 0.0005, -0.0002, -5e-4, 1e-4};
    case CameraModelId::kSimpleDivision:
      return {500, 320, 240, -0.05};
    case CameraModelId::kDivision:
      return {500, 505, 320, 240, -0.05};
    case CameraModelId::kSimpleFisheye:
      return {300, 320, 240};
    case CameraModelId::kFisheye:
      return {300, 305, 320, 240};
    case CameraModelId::kEUCM:
      return {300, 305, 320, 240, 0.6, 1.1};
    case CameraModelId::kEquirectangular:
      return {2048, 1024};
    case CameraModelId::kInvalid:
      break;
  }
  PARALLAX_CHECK_MSG(false, "no test parameters for camera model " << static_cast<int>(model_id));
}

// The largest angle from the optical axis (radians) the tests sample for a model: 40
// degrees for a perspective lens, 60 for a division lens, 95 (a 190-degree lens) for the
// fisheye family and EUCM, 180 for the sphere.
inline double TestHalfFieldOfView(CameraModelId model_id) {
  constexpr double kDegree = M_PI / 180.0;
  switch (model_id) {
    case CameraModelId::kSimpleDivision:
    case CameraModelId::kDivision:
      return 60 * kDegree;
    case CameraModelId::kEUCM:
      return 95 * kDegree;
    case CameraModelId::kEquirectangular:
      return 180 * kDegree;
    default:
      return CameraModelProjection(model_id) == CameraProjection::kFisheye ? 95 * kDegree
                                                                           : 40 * kDegree;
  }
}

// Unit rays spread over the test field of view of a model: rings of angles from the axis
// up to TestHalfFieldOfView (short of the poles and the back of the sphere), twelve
// directions each.
inline std::vector<Eigen::Vector3d> TestRays(CameraModelId model_id) {
  const double max_angle = std::min(TestHalfFieldOfView(model_id), M_PI - 0.05);
  std::vector<Eigen::Vector3d> rays = {Eigen::Vector3d::UnitZ()};
  for (int ring = 1; ring <= 8; ++ring) {
    const double theta = max_angle * ring / 8.0;
    for (int k = 0; k < 12; ++k) {
      const double phi = 2.0 * M_PI * (k + 0.25) / 12.0;
      Eigen::Vector3d ray(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                          std::cos(theta));
      // Keep clear of the sphere's poles (straight up or down), where azimuth is undefined.
      if (model_id == CameraModelId::kEquirectangular && std::abs(ray.y()) > 0.995) continue;
      rays.push_back(ray);
    }
  }
  return rays;
}

}  // namespace parallax
