#pragma once

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>

#include "parallax/geometry/camera_models.h"

namespace parallax {

// Reprojection error of one observation for camera model `CameraModel`:
//
//   r = pi_K(R X + t) - x
//
// where the pose cam_from_world is (q, t) with q an Eigen quaternion stored x, y, z, w
// (parameterise with ceres::EigenQuaternionManifold), X the 3D point, pi_K the model's
// projection with intrinsics `camera_params`, and x the observed keypoint in pixels.
// Parameter blocks: quaternion (4), translation (3), point (3), camera params (kNumParams).
template <typename CameraModel>
class ReprojectionErrorCostFunction {
 public:
  explicit ReprojectionErrorCostFunction(const Eigen::Vector2d& point2D) : observed_(point2D) {}

  static ceres::CostFunction* Create(const Eigen::Vector2d& point2D) {
    return new ceres::AutoDiffCostFunction<ReprojectionErrorCostFunction, 2, 4, 3, 3,
                                           CameraModel::kNumParams>(
        new ReprojectionErrorCostFunction(point2D));
  }

  template <typename T>
  bool operator()(const T* const cam_from_world_rotation, const T* const cam_from_world_translation,
                  const T* const point3D, const T* const camera_params, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(cam_from_world_rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(cam_from_world_translation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> point(point3D);
    const Eigen::Matrix<T, 3, 1> point_in_cam = rotation * point + translation;
    T x, y;
    CameraModel::ImgFromCam(camera_params, point_in_cam.x(), point_in_cam.y(), point_in_cam.z(), &x,
                            &y);
    residuals[0] = x - T(observed_.x());
    residuals[1] = y - T(observed_.y());
    return true;
  }

 private:
  const Eigen::Vector2d observed_;
};

// Creates the cost function for a runtime camera model id.
inline ceres::CostFunction* CreateReprojectionErrorCostFunction(CameraModelId model_id,
                                                                const Eigen::Vector2d& point2D) {
  return VisitCameraModel(model_id, [&]<typename Model>() -> ceres::CostFunction* {
    return ReprojectionErrorCostFunction<Model>::Create(point2D);
  });
}

}  // namespace parallax
