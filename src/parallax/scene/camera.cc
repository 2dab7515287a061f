#include "parallax/scene/camera.h"

#include <algorithm>
#include <cmath>

#include "parallax/util/check.h"

namespace parallax {

Camera Camera::Create(camera_t camera_id, CameraModelId model_id, double focal_length, size_t width,
                      size_t height) {
  Camera camera;
  camera.camera_id = camera_id;
  camera.model_id = model_id;
  camera.width = width;
  camera.height = height;
  camera.params = CameraModelInitialParams(model_id, focal_length, width / 2.0, height / 2.0);
  return camera;
}

double Camera::MeanFocalLength() const {
  if (CameraModelProjection(model_id) == CameraProjection::kSpherical) {
    return params.at(0) / (2.0 * M_PI);
  }
  const auto idxs = CameraModelFocalIdxs(model_id);
  double sum = 0;
  for (int idx : idxs) sum += params.at(idx);
  return sum / idxs.size();
}

namespace {

// The parameter at position `which` of a group, or a CheckError naming the model that has
// no such group (a spherical model has no focal length or principal point).
double GroupParam(const Camera& camera, const std::vector<int>& idxs, size_t which,
                  const char* group) {
  PARALLAX_CHECK_MSG(which < idxs.size() || (which == 1 && !idxs.empty()),
                     "a " << camera.ModelName() << " camera has no " << group);
  return camera.params.at(idxs.at(std::min(which, idxs.size() - 1)));
}

}  // namespace

double Camera::FocalLengthX() const {
  return GroupParam(*this, CameraModelFocalIdxs(model_id), 0, "focal length");
}
double Camera::FocalLengthY() const {
  return GroupParam(*this, CameraModelFocalIdxs(model_id), 1, "focal length");
}
double Camera::PrincipalPointX() const {
  return GroupParam(*this, CameraModelPrincipalPointIdxs(model_id), 0, "principal point");
}
double Camera::PrincipalPointY() const {
  return GroupParam(*this, CameraModelPrincipalPointIdxs(model_id), 1, "principal point");
}

void Camera::SetFocalLength(double focal_length) {
  for (int idx : CameraModelFocalIdxs(model_id)) params.at(idx) = focal_length;
}

Eigen::Matrix3d Camera::CalibrationMatrix() const {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = FocalLengthX();
  K(1, 1) = FocalLengthY();
  K(0, 2) = PrincipalPointX();
  K(1, 2) = PrincipalPointY();
  return K;
}

bool Camera::VerifyParams() const {
  if (!ExistsCameraModel(static_cast<int>(model_id))) return false;
  if (static_cast<int>(params.size()) != CameraModelNumParams(model_id)) return false;
  for (double value : params) {
    if (!std::isfinite(value)) return false;
  }
  for (int idx : CameraModelFocalIdxs(model_id)) {
    if (params[idx] <= 0) return false;
  }
  return true;
}

bool Camera::HasBogusParams(double min_focal_length_ratio, double max_focal_length_ratio,
                            double max_extra_param) const {
  const double max_size = static_cast<double>(std::max(width, height));
  for (int idx : CameraModelFocalIdxs(model_id)) {
    const double ratio = params[idx] / max_size;
    if (ratio < min_focal_length_ratio || ratio > max_focal_length_ratio) return true;
  }
  for (int idx : CameraModelExtraIdxs(model_id)) {
    if (std::abs(params[idx]) > max_extra_param) return true;
  }
  return false;
}

}  // namespace parallax
