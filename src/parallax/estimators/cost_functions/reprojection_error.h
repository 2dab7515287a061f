#pragma once

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "parallax/geometry/camera_models.h"

namespace parallax {

// pi_K(point_in_cam) in pixels with its Jacobian d_img_d_cam (2x3) and, when
// `d_img_d_params` is non-null, the Jacobian with respect to the intrinsics (2 x kNumParams,
// row-major). Only the projection is differentiated with dual numbers: 3 inputs, plus the
// intrinsics when asked for.
template <typename CameraModel>
inline void ProjectWithJacobians(const double* camera_params, const Eigen::Vector3d& point_in_cam,
                                 Eigen::Vector2d* img, Eigen::Matrix<double, 2, 3>* d_img_d_cam,
                                 double* d_img_d_params) {
  constexpr int kNumParams = CameraModel::kNumParams;
  if (d_img_d_params != nullptr) {
    using Jet = ceres::Jet<double, 3 + kNumParams>;
    Jet params_jet[kNumParams];
    for (int k = 0; k < kNumParams; ++k) params_jet[k] = Jet(camera_params[k], 3 + k);
    Jet x, y;
    CameraModel::ImgFromCam(params_jet, Jet(point_in_cam.x(), 0), Jet(point_in_cam.y(), 1),
                            Jet(point_in_cam.z(), 2), &x, &y);
    *img = Eigen::Vector2d(x.a, y.a);
    d_img_d_cam->row(0) = x.v.template head<3>().transpose();
    d_img_d_cam->row(1) = y.v.template head<3>().transpose();
    Eigen::Map<Eigen::Matrix<double, 2, kNumParams, Eigen::RowMajor>> d_params(d_img_d_params);
    d_params.row(0) = x.v.template tail<kNumParams>().transpose();
    d_params.row(1) = y.v.template tail<kNumParams>().transpose();
    return;
  }
  if constexpr (CameraModel::kProjection == CameraProjection::kPerspective &&
                !CameraModel::kHasClosedForm && CameraModel::kNumExtraParams == 0) {
    // A pinhole's Jacobian by hand: the dual numbers cost more than the rest of a bundle
    // adjustment's linearisation. Written as Ceres' Jet arithmetic evaluates it (the
    // quotient as a product with 1/w), so that both give the same bits.
    const double fx = camera_params[CameraModel::kFocalIdxs.front()];
    const double fy = camera_params[CameraModel::kFocalIdxs.back()];
    const double inverse_w = 1.0 / point_in_cam.z();
    const double x_over_w = (fx * point_in_cam.x()) * inverse_w;
    const double y_over_w = (fy * point_in_cam.y()) * inverse_w;
    *img = Eigen::Vector2d(x_over_w + camera_params[CameraModel::kPrincipalPointIdxs[0]],
                           y_over_w + camera_params[CameraModel::kPrincipalPointIdxs[1]]);
    *d_img_d_cam << fx * inverse_w, 0.0, -x_over_w * inverse_w,  //
        0.0, fy * inverse_w, -y_over_w * inverse_w;
    return;
  }
  using Jet = ceres::Jet<double, 3>;
  Jet params_jet[kNumParams];
  for (int k = 0; k < kNumParams; ++k) params_jet[k] = Jet(camera_params[k]);
  Jet x, y;
  CameraModel::ImgFromCam(params_jet, Jet(point_in_cam.x(), 0), Jet(point_in_cam.y(), 1),
                          Jet(point_in_cam.z(), 2), &x, &y);
  *img = Eigen::Vector2d(x.a, y.a);
  d_img_d_cam->row(0) = x.v.transpose();
  d_img_d_cam->row(1) = y.v.transpose();
}

// Reprojection error of one observation for camera model `CameraModel`:
//
//   r = pi_K(R X + t) - x
//
// where the pose cam_from_world is (q, t) with q an Eigen quaternion stored x, y, z, w
// (parameterise with ceres::EigenQuaternionManifold), X the 3D point, pi_K the model's
// projection with intrinsics `camera_params`, and x the observed keypoint in pixels.
// Parameter blocks: quaternion (4), translation (3), point (3), camera params (kNumParams).
//
// This functor is the definition, differentiated automatically; the cost function below
// computes the same residual with analytic pose and point Jacobians and is what bundle
// adjustment uses. Tests hold the two to each other.
template <typename CameraModel>
struct ReprojectionErrorFunctor {
  explicit ReprojectionErrorFunctor(const Eigen::Vector2d& point2D) : observed(point2D) {}

  static ceres::CostFunction* CreateAutoDiff(const Eigen::Vector2d& point2D) {
    return new ceres::AutoDiffCostFunction<ReprojectionErrorFunctor, 2, 4, 3, 3,
                                           CameraModel::kNumParams>(
        new ReprojectionErrorFunctor(point2D));
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
    residuals[0] = x - T(observed.x());
    residuals[1] = y - T(observed.y());
    return true;
  }

  const Eigen::Vector2d observed;
};

// The reprojection error with analytic Jacobians. Bundle adjustment spends most of its time
// evaluating these: automatic differentiation carries a 4+3+3+kNumParams dual number through
// the whole rotation even when the camera is constant. Here only the projection pi_K is
// differentiated with dual numbers (3 inputs, plus the intrinsics when they are refined);
// the chain rule through R X + t is written out. The quaternion Jacobian is the ambient one
// (with respect to x, y, z, w of the same polynomial Eigen evaluates), so it composes with
// ceres::EigenQuaternionManifold exactly as the automatic one does.
template <typename CameraModel>
class ReprojectionErrorCostFunction
    : public ceres::SizedCostFunction<2, 4, 3, 3, CameraModel::kNumParams> {
 public:
  static constexpr int kNumParams = CameraModel::kNumParams;

  explicit ReprojectionErrorCostFunction(const Eigen::Vector2d& point2D) : observed_(point2D) {}

  static ceres::CostFunction* Create(const Eigen::Vector2d& point2D) {
    return new ReprojectionErrorCostFunction(point2D);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* q = parameters[0];
    const double* t = parameters[1];
    const Eigen::Vector3d point(parameters[2][0], parameters[2][1], parameters[2][2]);
    const double* camera_params = parameters[3];

    // R X as Eigen computes it for a unit quaternion: X + 2w (v x X) + 2 v x (v x X).
    const Eigen::Vector3d v(q[0], q[1], q[2]);
    const double w = q[3];
    const Eigen::Vector3d v_cross_x = v.cross(point);
    const Eigen::Vector3d point_in_cam =
        point + 2.0 * w * v_cross_x + 2.0 * v.cross(v_cross_x) + Eigen::Vector3d(t[0], t[1], t[2]);

    if (jacobians == nullptr) {
      double x, y;
      CameraModel::ImgFromCam(camera_params, point_in_cam.x(), point_in_cam.y(), point_in_cam.z(),
                              &x, &y);
      residuals[0] = x - observed_.x();
      residuals[1] = y - observed_.y();
      return true;
    }

    // d pi / d point_in_cam (2x3), and d pi / d params (2xP) when asked for.
    Eigen::Matrix<double, 2, 3> d_img_d_cam;
    Eigen::Vector2d img;
    ProjectWithJacobians<CameraModel>(camera_params, point_in_cam, &img, &d_img_d_cam,
                                      jacobians[3]);
    residuals[0] = img.x() - observed_.x();
    residuals[1] = img.y() - observed_.y();

    if (jacobians[0] != nullptr) {
      // d(R X)/dv = -2w [X]x + 2((v.X) I + v X^T - 2 X v^T);  d(R X)/dw = 2 v x X.
      Eigen::Matrix3d skew_point;
      skew_point << 0, -point.z(), point.y(), point.z(), 0, -point.x(), -point.y(), point.x(), 0;
      Eigen::Matrix<double, 3, 4> d_cam_d_q;
      d_cam_d_q.leftCols<3>() =
          -2.0 * w * skew_point + 2.0 * (v.dot(point) * Eigen::Matrix3d::Identity() +
                                         v * point.transpose() - 2.0 * point * v.transpose());
      d_cam_d_q.col(3) = 2.0 * v_cross_x;
      Eigen::Map<Eigen::Matrix<double, 2, 4, Eigen::RowMajor>> d_q(jacobians[0]);
      d_q = d_img_d_cam * d_cam_d_q;
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> d_t(jacobians[1]);
      d_t = d_img_d_cam;
    }
    if (jacobians[2] != nullptr) {
      // d(R X)/dX = I + 2w [v]x + 2 [v]x^2 (R itself for a unit quaternion).
      Eigen::Matrix3d skew_v;
      skew_v << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
      const Eigen::Matrix3d d_cam_d_point =
          Eigen::Matrix3d::Identity() + 2.0 * w * skew_v + 2.0 * skew_v * skew_v;
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> d_point(jacobians[2]);
      d_point = d_img_d_cam * d_cam_d_point;
    }
    return true;
  }

 private:
  const Eigen::Vector2d observed_;
};

// Creates the cost function for a runtime camera model id (reprojection_error.cc: every
// model's cost function compiled once).
ceres::CostFunction* CreateReprojectionErrorCostFunction(CameraModelId model_id,
                                                         const Eigen::Vector2d& point2D);

}  // namespace parallax
