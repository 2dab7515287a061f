#include "parallax/geometry/camera_models.h"

#include <Eigen/LU>
#include <cmath>

#include "parallax/util/check.h"

namespace parallax {

template <typename Traits>
Eigen::Vector2d CameraModel<Traits>::CamFromImg(const double* params, const Eigen::Vector2d& xy) {
  // Undo focal length and principal point: distorted normalised coordinates.
  const double fx = params[Traits::kFocalIdxs.front()];
  const double fy = params[Traits::kFocalIdxs.back()];
  const Eigen::Vector2d distorted((xy.x() - params[Traits::kPrincipalPointIdxs[0]]) / fx,
                                  (xy.y() - params[Traits::kPrincipalPointIdxs[1]]) / fy);
  if constexpr (kNumExtraParams == 0) {
    return distorted;
  } else {
    // Solve u + d(u) = distorted for u with Newton steps and a numeric Jacobian of d.
    Eigen::Vector2d undistorted = distorted;
    constexpr int kMaxIterations = 100;
    constexpr double kStep = 1e-7;
    const auto apply = [&](const Eigen::Vector2d& u) {
      Eigen::Vector2d d;
      Traits::Distortion(params, u.x(), u.y(), &d.x(), &d.y());
      return Eigen::Vector2d(u + d);
    };
    for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
      const Eigen::Vector2d residual = apply(undistorted) - distorted;
      Eigen::Matrix2d jacobian;
      for (int axis = 0; axis < 2; ++axis) {
        Eigen::Vector2d shifted = undistorted;
        const double h = kStep * std::max(1.0, std::abs(undistorted(axis)));
        shifted(axis) += h;
        jacobian.col(axis) = (apply(shifted) - apply(undistorted)) / h;
      }
      const Eigen::Vector2d step = jacobian.partialPivLu().solve(residual);
      if (!step.allFinite()) break;
      undistorted -= step;
      if (step.squaredNorm() < 1e-24) break;
    }
    return undistorted;
  }
}

// The registered models' CamFromImg, compiled here once.
#define PARALLAX_CAMERA_MODEL_INSTANCE(Name) template struct CameraModel<Name##Traits>;
PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_INSTANCE)
#undef PARALLAX_CAMERA_MODEL_INSTANCE

void ThrowInvalidCameraModel(int model_id) {
  PARALLAX_CHECK_MSG(false, "invalid camera model id " << model_id);
}

bool ExistsCameraModel(int model_id) {
  // A case per registered model: two models with one id do not compile.
  switch (model_id) {
#define PARALLAX_CAMERA_MODEL_CASE(Name) case Name##Traits::kColmapId:
    PARALLAX_CAMERA_MODELS(PARALLAX_CAMERA_MODEL_CASE)
#undef PARALLAX_CAMERA_MODEL_CASE
    return true;
    default:
      return false;
  }
}

std::string CameraModelName(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() { return std::string(Model::kName); });
}

CameraModelId CameraModelIdFromName(const std::string& name) {
  for (const CameraModelId id : kCameraModelIds) {
    if (CameraModelName(id) == name) return id;
  }
  return CameraModelId::kInvalid;
}

std::string CameraModelParamsInfo(CameraModelId model_id) {
  return VisitCameraModel(model_id,
                          []<typename Model>() { return std::string(Model::kParamsInfo); });
}

int CameraModelNumParams(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() { return Model::kNumParams; });
}

std::vector<int> CameraModelFocalIdxs(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() {
    return std::vector<int>(Model::kFocalIdxs.begin(), Model::kFocalIdxs.end());
  });
}

std::vector<int> CameraModelPrincipalPointIdxs(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() {
    return std::vector<int>(Model::kPrincipalPointIdxs.begin(), Model::kPrincipalPointIdxs.end());
  });
}

std::vector<int> CameraModelExtraIdxs(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() {
    return std::vector<int>(Model::kExtraIdxs.begin(), Model::kExtraIdxs.end());
  });
}

std::vector<double> CameraModelInitialParams(CameraModelId model_id, double focal_length,
                                             double principal_point_x, double principal_point_y) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    std::vector<double> params(Model::kNumParams, 0.0);
    for (int idx : Model::kFocalIdxs) params[idx] = focal_length;
    params[Model::kPrincipalPointIdxs[0]] = principal_point_x;
    params[Model::kPrincipalPointIdxs[1]] = principal_point_y;
    return params;
  });
}

Eigen::Vector2d CameraModelImgFromCam(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector3d& point_in_cam) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    Eigen::Vector2d xy;
    Model::ImgFromCam(params.data(), point_in_cam.x(), point_in_cam.y(), point_in_cam.z(), &xy.x(),
                      &xy.y());
    return xy;
  });
}

Eigen::Vector2d CameraModelCamFromImg(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector2d& xy) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    return Model::CamFromImg(params.data(), xy);
  });
}

}  // namespace parallax
