#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "parallax/geometry/camera_models.h"
#include "parallax/util/types.h"

namespace parallax {

// Intrinsics of one physical camera, shared by the images taken with it.
struct Camera {
  camera_t camera_id = kInvalidCameraId;
  CameraModelId model_id = CameraModelId::kInvalid;
  size_t width = 0;
  size_t height = 0;
  std::vector<double> params;
  // True when the intrinsics are known (calibration, K, the user's parameters): bundle
  // adjustment holds them fixed. An EXIF focal length is not known, only a good start.
  bool has_prior_focal_length = false;
  // True when the initial focal length came from EXIF (a database stores it as COLMAP's
  // prior_focal_length = 1, which COLMAP needs to map fisheyes).
  bool focal_length_from_exif = false;

  // A camera with the principal point at the image centre and zero distortion.
  static Camera Create(camera_t camera_id, CameraModelId model_id, double focal_length,
                       size_t width, size_t height);

  std::string ModelName() const { return CameraModelName(model_id); }
  // The mean of the focal lengths; a spherical camera's pixels per radian on the equator.
  double MeanFocalLength() const;
  double FocalLengthX() const;
  double FocalLengthY() const;
  double PrincipalPointX() const;
  double PrincipalPointY() const;
  void SetFocalLength(double focal_length);
  // K built from focal lengths and principal point (distortion ignored).
  Eigen::Matrix3d CalibrationMatrix() const;
  // True when params has the model's size and focal lengths are positive and finite.
  bool VerifyParams() const;
  // True when focal lengths or distortion drifted implausibly during refinement.
  bool HasBogusParams(double min_focal_length_ratio, double max_focal_length_ratio,
                      double max_extra_param) const;

  Eigen::Vector2d ImgFromCam(const Eigen::Vector3d& point_in_cam) const {
    return CameraModelImgFromCam(model_id, params, point_in_cam);
  }
  // Normalised coordinates (z = 1) of a pixel, for rays in front of the camera.
  Eigen::Vector2d CamFromImg(const Eigen::Vector2d& xy) const {
    return CameraModelCamFromImg(model_id, params, xy);
  }
  // The unit ray of a pixel, in front of the camera or (wide lenses) behind it.
  Eigen::Vector3d CamRayFromImg(const Eigen::Vector2d& xy) const {
    return CameraModelCamRayFromImg(model_id, params, xy);
  }
  // A pixel threshold expressed in normalised coordinates (radians near the axis).
  double CamFromImgThreshold(double threshold_px) const {
    return CameraModelCamFromImgThreshold(model_id, params, threshold_px);
  }
  CameraProjection Projection() const { return CameraModelProjection(model_id); }
};

}  // namespace parallax
