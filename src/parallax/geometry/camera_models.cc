#include "parallax/geometry/camera_models.h"

#include <Eigen/LU>
#include <cmath>

#include "parallax/util/check.h"

namespace parallax {

namespace {

// Solves p + d(p) = distorted for p by Newton steps with a numeric Jacobian of d. Each step
// is limited to a tenth of |p| (at least 0.1): strong fisheye distortion bends d enough
// that full steps overshoot far from the axis.
template <typename Distort>
Eigen::Vector2d InvertDistortion(const Distort& distort, const Eigen::Vector2d& distorted) {
  constexpr int kMaxIterations = 100;
  constexpr double kStep = 1e-7;
  constexpr double kRelativeRadius = 0.1, kMinRadius = 0.1;
  const auto apply = [&](const Eigen::Vector2d& p) { return Eigen::Vector2d(p + distort(p)); };
  Eigen::Vector2d undistorted = distorted;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const Eigen::Vector2d residual = apply(undistorted) - distorted;
    Eigen::Matrix2d jacobian;
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::Vector2d shifted = undistorted;
      const double h = kStep * std::max(1.0, std::abs(undistorted(axis)));
      shifted(axis) += h;
      jacobian.col(axis) = (apply(shifted) - apply(undistorted)) / h;
    }
    Eigen::Vector2d step = jacobian.partialPivLu().solve(residual);
    if (!step.allFinite()) break;
    const double radius = std::max(kRelativeRadius * undistorted.norm(), kMinRadius);
    if (step.norm() > radius) step *= radius / step.norm();
    undistorted -= step;
    if (step.squaredNorm() < 1e-24) break;
  }
  return undistorted;
}

}  // namespace

// Normalised (or, for a fisheye, fisheye) coordinates of a pixel with the distortion undone:
// focal length and principal point removed, then InvertDistortion. Both unprojections of the
// models without a closed form start from these.
template <typename Traits>
Eigen::Vector2d UndistortedCoordinates(const double* params, const Eigen::Vector2d& xy) {
  const double fx = params[Traits::kFocalIdxs.front()];
  const double fy = params[Traits::kFocalIdxs.back()];
  const Eigen::Vector2d distorted((xy.x() - params[Traits::kPrincipalPointIdxs[0]]) / fx,
                                  (xy.y() - params[Traits::kPrincipalPointIdxs[1]]) / fy);
  if constexpr (CameraModel<Traits>::kNumExtraParams == 0) {
    return distorted;
  } else {
    return InvertDistortion(
        [&](const Eigen::Vector2d& p) {
          Eigen::Vector2d d;
          Traits::Distortion(params, p.x(), p.y(), &d.x(), &d.y());
          return d;
        },
        distorted);
  }
}

template <typename Traits>
Eigen::Vector3d CameraModel<Traits>::CamRayFromImg(const double* params,
                                                   const Eigen::Vector2d& xy) {
  if constexpr (kHasClosedForm) {
    return Traits::Unproject(params, xy);
  } else {
    const Eigen::Vector2d undistorted = UndistortedCoordinates<Traits>(params, xy);
    if constexpr (kProjection == CameraProjection::kPerspective) {
      return undistorted.homogeneous().normalized();
    } else {
      // Fisheye coordinates: direction (u, v) / theta at the angle theta = |(u, v)|.
      const double theta = undistorted.norm();
      if (theta < 1e-12) return undistorted.homogeneous().normalized();
      const Eigen::Vector2d side = std::sin(theta) / theta * undistorted;
      return Eigen::Vector3d(side.x(), side.y(), std::cos(theta));
    }
  }
}

template <typename Traits>
Eigen::Vector2d CameraModel<Traits>::CamFromImg(const double* params, const Eigen::Vector2d& xy) {
  if constexpr (kProjection == CameraProjection::kPerspective && !kHasClosedForm) {
    // Straight from the undistorted normalised coordinates: no ray to normalise.
    return UndistortedCoordinates<Traits>(params, xy);
  } else {
    return CamRayFromImg(params, xy).hnormalized();
  }
}

template <typename Traits>
double CameraModel<Traits>::CamFromImgThreshold(const double* params, double threshold) {
  if constexpr (kProjection == CameraProjection::kSpherical) {
    return threshold * 2.0 * M_PI / params[0];
  } else {
    double focal_sum = 0;
    for (int idx : Traits::kFocalIdxs) focal_sum += params[idx];
    return threshold * static_cast<double>(Traits::kFocalIdxs.size()) / focal_sum;
  }
}

// The registered models' unprojections, compiled here once.
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

CameraProjection CameraModelProjection(CameraModelId model_id) {
  return VisitCameraModel(model_id, []<typename Model>() { return Model::kProjection; });
}

std::vector<double> CameraModelInitialParams(CameraModelId model_id, double focal_length,
                                             double principal_point_x, double principal_point_y) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    std::vector<double> params(Model::kNumParams, 0.0);
    if constexpr (Model::kProjection == CameraProjection::kSpherical) {
      params[0] = 2.0 * principal_point_x;
      params[1] = 2.0 * principal_point_y;
    } else {
      for (int idx : Model::kFocalIdxs) params[idx] = focal_length;
      params[Model::kPrincipalPointIdxs[0]] = principal_point_x;
      params[Model::kPrincipalPointIdxs[1]] = principal_point_y;
      for (int i = 0; i < Model::kNumExtraParams; ++i) {
        params[Model::kExtraIdxs[i]] = Model::kInitialExtraParams[i];
      }
    }
    return params;
  });
}

bool CameraModelProjects(CameraModelId model_id, const std::vector<double>& params,
                         const Eigen::Vector3d& point_in_cam, Eigen::Vector2d* xy) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    return Model::ImgFromCam(params.data(), point_in_cam.x(), point_in_cam.y(), point_in_cam.z(),
                             &xy->x(), &xy->y());
  });
}

Eigen::Vector2d CameraModelImgFromCam(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector3d& point_in_cam) {
  Eigen::Vector2d xy;
  CameraModelProjects(model_id, params, point_in_cam, &xy);
  return xy;
}

Eigen::Vector2d CameraModelCamFromImg(CameraModelId model_id, const std::vector<double>& params,
                                      const Eigen::Vector2d& xy) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    return Model::CamFromImg(params.data(), xy);
  });
}

Eigen::Vector3d CameraModelCamRayFromImg(CameraModelId model_id, const std::vector<double>& params,
                                         const Eigen::Vector2d& xy) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    return Model::CamRayFromImg(params.data(), xy);
  });
}

double CameraModelCamFromImgThreshold(CameraModelId model_id, const std::vector<double>& params,
                                      double threshold) {
  return VisitCameraModel(model_id, [&]<typename Model>() {
    PARALLAX_CHECK_EQ(static_cast<int>(params.size()), Model::kNumParams);
    return Model::CamFromImgThreshold(params.data(), threshold);
  });
}

}  // namespace parallax
