#include "parallax/estimators/absolute_pose.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>

#include "parallax/estimators/cost_functions/reprojection_error.h"
#include "parallax/estimators/solvers/epnp.h"
#include "parallax/estimators/solvers/p3p.h"
#include "parallax/estimators/solvers/pose_levenberg_marquardt.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {

void AbsolutePoseEstimationOptions::Check() const { ransac.Check(); }

void AbsolutePoseRefinementOptions::Check() const {
  PARALLAX_CHECK_GT(loss_scale_px, 0.0);
  PARALLAX_CHECK_GT(max_num_iterations, 0);
  PARALLAX_CHECK_GE(min_relative_decrease, 0.0);
}

AbsolutePoseReport EstimateAbsolutePose(const Camera& camera,
                                        const std::vector<Eigen::Vector2d>& points2D,
                                        const std::vector<Eigen::Vector3d>& points3D,
                                        const AbsolutePoseEstimationOptions& options) {
  options.Check();
  PARALLAX_CHECK_EQ(points2D.size(), points3D.size());
  AbsolutePoseReport report;
  report.inlier_mask.assign(points2D.size(), 0);
  if (!camera.VerifyParams()) return report;

  // Undistorted normalised points; non-finite correspondences take no part.
  std::vector<Eigen::Vector2d> normalized_points;
  std::vector<Eigen::Vector3d> world_points;
  std::vector<size_t> original_indices;
  normalized_points.reserve(points2D.size());
  world_points.reserve(points2D.size());
  original_indices.reserve(points2D.size());
  for (size_t i = 0; i < points2D.size(); ++i) {
    if (!points2D[i].allFinite() || !points3D[i].allFinite()) continue;
    const Eigen::Vector2d normalized = camera.CamFromImg(points2D[i]);
    if (!normalized.allFinite()) continue;
    normalized_points.push_back(normalized);
    world_points.push_back(points3D[i]);
    original_indices.push_back(i);
  }
  // Three points give up to four poses and no way to choose.
  if (normalized_points.size() < static_cast<size_t>(EPnPEstimator::kMinNumSamples)) return report;

  RansacOptions ransac_options = options.ransac;
  ransac_options.max_error = camera.CamFromImgThreshold(options.ransac.max_error);
  if (!(ransac_options.max_error > 0) || !std::isfinite(ransac_options.max_error)) return report;
  const LoRansac<P3PEstimator, EPnPEstimator> ransac(ransac_options);
  const RansacReport<Rigid3d> ransac_report = ransac.Estimate(normalized_points, world_points);
  report.num_trials = ransac_report.num_trials;
  if (!ransac_report.success) return report;

  report.success = true;
  report.cam_from_world = ransac_report.model;
  report.num_inliers = ransac_report.num_inliers;
  for (size_t i = 0; i < original_indices.size(); ++i) {
    report.inlier_mask[original_indices[i]] = ransac_report.inlier_mask[i];
  }
  return report;
}

namespace {

// Cauchy's loss on the squared reprojection error, scaled as ceres::CauchyLoss is.
struct CauchyLoss {
  double squared_scale;
  double Cost(double squared_norm) const {
    return squared_scale * std::log1p(squared_norm / squared_scale);
  }
  double Weight(double squared_norm) const { return 1 / (1 + squared_norm / squared_scale); }
};

// The mapper's case, intrinsics constant: six unknowns and thousands of residuals, solved
// directly rather than through a Ceres problem of one block per point (about four times
// the cost per image for the same minimum).
bool RefinePoseOnly(const AbsolutePoseRefinementOptions& options,
                    const std::vector<Eigen::Vector2d>& points2D,
                    const std::vector<size_t>& observation_indices,
                    const std::vector<Eigen::Vector3d>& points, Rigid3d* cam_from_world,
                    const Camera& camera) {
  Eigen::Matrix3d rotation = cam_from_world->rotation.toRotationMatrix();
  Eigen::Vector3d translation = cam_from_world->translation;
  const double* params = camera.params.data();
  PoseLevenbergMarquardtOptions lm_options;
  lm_options.max_num_iterations = options.max_num_iterations;
  lm_options.min_relative_decrease = options.min_relative_decrease;
  // The model's projection through function pointers: one instantiation of the pose
  // minimisation for every model (18 would cost the build more than the calls cost it).
  using ProjectFn = void (*)(const double*, const Eigen::Vector3d&, Eigen::Vector2d*,
                             Eigen::Matrix<double, 2, 3>*, double*);
  using ImgFromCamFn = bool (*)(const double*, double, double, double, double*, double*);
  const ProjectFn project = VisitCameraModel(
      camera.model_id, []<typename Model>() -> ProjectFn { return &ProjectWithJacobians<Model>; });
  const ImgFromCamFn img_from_cam = VisitCameraModel(
      camera.model_id,
      []<typename Model>() -> ImgFromCamFn { return &Model::template ImgFromCam<double>; });
  // A perspective lens sees only what is in front of it; a wider one whatever it projects.
  const bool perspective = camera.Projection() == CameraProjection::kPerspective;
  const auto observe = [&](size_t k, const Eigen::Vector3d& point_in_cam, Eigen::Vector2d* residual,
                           Eigen::Matrix<double, 2, 3>* jacobian) {
    if (perspective && !(point_in_cam.z() > std::numeric_limits<double>::epsilon())) return false;
    Eigen::Vector2d projection;
    if (jacobian == nullptr || !perspective) {
      const bool projects = img_from_cam(params, point_in_cam.x(), point_in_cam.y(),
                                         point_in_cam.z(), &projection.x(), &projection.y());
      if (!perspective && !projects) return false;
    }
    if (jacobian != nullptr) project(params, point_in_cam, &projection, jacobian, nullptr);
    *residual = projection - points2D[observation_indices[k]];
    return true;
  };
  const CauchyLoss loss{options.loss_scale_px * options.loss_scale_px};
  const bool solved = MinimizeOverPose(points, observe, loss, lm_options, &rotation, &translation);
  if (!solved || !rotation.allFinite() || !translation.allFinite()) return false;
  cam_from_world->rotation = Eigen::Quaterniond(rotation).normalized();
  cam_from_world->translation = translation;
  return true;
}

}  // namespace

bool RefineAbsolutePose(const AbsolutePoseRefinementOptions& options,
                        const std::vector<char>& inlier_mask,
                        const std::vector<Eigen::Vector2d>& points2D,
                        const std::vector<Eigen::Vector3d>& points3D, Rigid3d* cam_from_world,
                        Camera* camera) {
  options.Check();
  PARALLAX_CHECK(cam_from_world != nullptr);
  PARALLAX_CHECK(camera != nullptr);
  PARALLAX_CHECK_EQ(points2D.size(), points3D.size());
  PARALLAX_CHECK_EQ(inlier_mask.size(), points2D.size());
  if (!camera->VerifyParams() || !cam_from_world->rotation.coeffs().allFinite() ||
      !cam_from_world->translation.allFinite() || cam_from_world->rotation.norm() == 0) {
    return false;
  }

  const Rigid3d initial_cam_from_world = *cam_from_world;
  const std::vector<double> initial_params = camera->params;
  cam_from_world->rotation.normalize();

  // The points are constant parameter blocks: copies, since the inputs are const.
  std::vector<Eigen::Vector3d> points;
  std::vector<size_t> observation_indices;
  for (size_t i = 0; i < points2D.size(); ++i) {
    if (!inlier_mask[i] || !points2D[i].allFinite() || !points3D[i].allFinite()) continue;
    // A point at or behind the camera has no usable projection.
    if (!((*cam_from_world * points3D[i]).z() > std::numeric_limits<double>::epsilon())) continue;
    points.push_back(points3D[i]);
    observation_indices.push_back(i);
  }
  if (points.size() < 3) return false;
  if (!options.refine_focal_length && !options.refine_extra_params) {
    return RefinePoseOnly(options, points2D, observation_indices, points, cam_from_world, *camera);
  }

  ceres::Problem problem;
  ceres::LossFunction* loss = new ceres::CauchyLoss(options.loss_scale_px);
  double* rotation = cam_from_world->rotation.coeffs().data();
  double* translation = cam_from_world->translation.data();
  double* params = camera->params.data();
  for (size_t k = 0; k < points.size(); ++k) {
    problem.AddResidualBlock(
        CreateReprojectionErrorCostFunction(camera->model_id, points2D[observation_indices[k]]),
        loss, rotation, translation, points[k].data(), params);
    problem.SetParameterBlockConstant(points[k].data());
  }
  problem.SetManifold(rotation, new ceres::EigenQuaternionManifold);

  // Camera intrinsics: constant, or a subset with the principal point always fixed.
  std::vector<int> constant_params = CameraModelPrincipalPointIdxs(camera->model_id);
  if (!options.refine_focal_length) {
    for (int idx : CameraModelFocalIdxs(camera->model_id)) constant_params.push_back(idx);
  }
  if (!options.refine_extra_params) {
    for (int idx : CameraModelExtraIdxs(camera->model_id)) constant_params.push_back(idx);
  }
  const int num_params = static_cast<int>(camera->params.size());
  if (static_cast<int>(constant_params.size()) >= num_params) {
    problem.SetParameterBlockConstant(params);
  } else {
    problem.SetManifold(params, new ceres::SubsetManifold(num_params, constant_params));
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_num_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  const bool usable = summary.IsSolutionUsable() && cam_from_world->rotation.coeffs().allFinite() &&
                      cam_from_world->translation.allFinite() && camera->VerifyParams();
  if (!usable) {
    PARALLAX_LOG(Debug) << "Absolute pose refinement failed: " << summary.BriefReport();
    *cam_from_world = initial_cam_from_world;
    camera->params = initial_params;
    return false;
  }
  cam_from_world->rotation.normalize();
  return true;
}

}  // namespace parallax
