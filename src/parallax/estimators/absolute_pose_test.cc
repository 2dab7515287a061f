#include "parallax/estimators/absolute_pose.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <cmath>
#include <limits>

#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::Rigid3dNear;

struct Scene {
  Camera camera;
  Rigid3d cam_from_world;
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector2d> true_points2D;  // Noise-free projections.
  std::vector<Eigen::Vector3d> points3D;
  std::vector<char> is_outlier;
};

Camera MakeCamera(CameraModelId model_id) {
  Camera camera = Camera::Create(1, model_id, 1000, 1000, 800);
  if (model_id == CameraModelId::kSimpleRadial) camera.params[3] = -0.08;
  if (model_id == CameraModelId::kOpenCV) {
    camera.params[4] = -0.1;
    camera.params[5] = 0.02;
    camera.params[6] = 1e-3;
    camera.params[7] = -5e-4;
  }
  return camera;
}

// Points seen anywhere in the image at depths 4 to 12; pixel noise, then a fraction of the
// observations replaced by random pixels.
Scene RandomScene(const Camera& camera, size_t num_points, double noise_px, double outlier_ratio) {
  Scene scene;
  scene.camera = camera;
  scene.cam_from_world = test::RandomCamFromWorld(3);
  const Rigid3d world_from_cam = scene.cam_from_world.Inverse();
  for (size_t i = 0; i < num_points; ++i) {
    const Eigen::Vector2d pixel(RandomUniformReal(0, camera.width),
                                RandomUniformReal(0, camera.height));
    const Eigen::Vector3d point_in_cam =
        RandomUniformReal(4, 12) * camera.CamFromImg(pixel).homogeneous();
    scene.points3D.push_back(world_from_cam * point_in_cam);
    scene.true_points2D.push_back(camera.ImgFromCam(point_in_cam));
    const bool outlier = RandomUniformReal(0, 1) < outlier_ratio;
    scene.is_outlier.push_back(outlier);
    if (outlier) {
      scene.points2D.push_back(
          Eigen::Vector2d(RandomUniformReal(0, camera.width), RandomUniformReal(0, camera.height)));
    } else {
      scene.points2D.push_back(
          scene.true_points2D.back() +
          Eigen::Vector2d(RandomGaussian(0, noise_px), RandomGaussian(0, noise_px)));
    }
  }
  return scene;
}

double RotationErrorDegrees(const Rigid3d& estimate, const Rigid3d& truth) {
  return RotationAngleDegrees(estimate.rotation, truth.rotation);
}

// Mean distance in pixels between the projections under `cam_from_world` and the noise-free
// projections of the true inliers: the pose error as the image sees it.
double MeanProjectionError(const Scene& scene, const Rigid3d& cam_from_world,
                           const Camera& camera) {
  double sum = 0;
  int count = 0;
  for (size_t i = 0; i < scene.points3D.size(); ++i) {
    if (scene.is_outlier[i]) continue;
    sum += (camera.ImgFromCam(cam_from_world * scene.points3D[i]) - scene.true_points2D[i]).norm();
    ++count;
  }
  return sum / count;
}

// Robust objective of RefineAbsolutePose: sum of a^2 log(1 + r^2 / a^2) over the inliers.
double CauchyCost(const Scene& scene, const std::vector<char>& inlier_mask,
                  const Rigid3d& cam_from_world, double scale_px) {
  double cost = 0;
  for (size_t i = 0; i < scene.points3D.size(); ++i) {
    if (!inlier_mask[i]) continue;
    const double squared_error =
        (scene.camera.ImgFromCam(cam_from_world * scene.points3D[i]) - scene.points2D[i])
            .squaredNorm();
    cost += scale_px * scale_px * std::log1p(squared_error / (scale_px * scale_px));
  }
  return cost;
}

void ExpectGoodInlierSet(const Scene& scene, const AbsolutePoseReport& report) {
  size_t num_true_inliers = 0, num_kept_inliers = 0, num_outliers = 0, num_kept_outliers = 0;
  ASSERT_EQ(report.inlier_mask.size(), scene.points2D.size());
  for (size_t i = 0; i < scene.points2D.size(); ++i) {
    if (scene.is_outlier[i]) {
      ++num_outliers;
      num_kept_outliers += report.inlier_mask[i];
    } else {
      ++num_true_inliers;
      num_kept_inliers += report.inlier_mask[i];
    }
  }
  EXPECT_GE(num_kept_inliers, 0.95 * num_true_inliers);
  EXPECT_LE(num_kept_outliers, 0.01 * num_outliers);
  EXPECT_EQ(report.num_inliers, num_kept_inliers + num_kept_outliers);
}

TEST(EstimateAbsolutePose, ExactCorrespondences) {
  for (CameraModelId model_id : {CameraModelId::kSimplePinhole, CameraModelId::kOpenCV}) {
    const Scene scene = RandomScene(MakeCamera(model_id), 100, 0, 0);
    const AbsolutePoseReport report =
        EstimateAbsolutePose(scene.camera, scene.points2D, scene.points3D, {});
    ASSERT_TRUE(report.success);
    EXPECT_EQ(report.num_inliers, 100u);
    EXPECT_THAT(report.cam_from_world, Rigid3dNear(scene.cam_from_world, 1e-8,
                                                   1e-8 * scene.cam_from_world.translation.norm()));
  }
}

TEST(EstimateAbsolutePose, NoiseAndFortyPercentOutliers) {
  const AbsolutePoseRefinementOptions refinement_options;
  double sum_error = 0, sum_refined_error = 0;
  for (CameraModelId model_id : {CameraModelId::kSimpleRadial, CameraModelId::kPinhole}) {
    for (double max_error_px : {12.0, 3.0}) {
      for (int trial = 0; trial < 5; ++trial) {
        const Scene scene = RandomScene(MakeCamera(model_id), 500, 0.5, 0.4);
        AbsolutePoseEstimationOptions options;
        options.ransac.max_error = max_error_px;
        const AbsolutePoseReport report =
            EstimateAbsolutePose(scene.camera, scene.points2D, scene.points3D, options);
        ASSERT_TRUE(report.success);
        ExpectGoodInlierSet(scene, report);
        EXPECT_LT(RotationErrorDegrees(report.cam_from_world, scene.cam_from_world), 0.1);

        Rigid3d refined = report.cam_from_world;
        Camera camera = scene.camera;
        ASSERT_TRUE(RefineAbsolutePose(refinement_options, report.inlier_mask, scene.points2D,
                                       scene.points3D, &refined, &camera));
        EXPECT_EQ(camera.params, scene.camera.params);  // Intrinsics constant by default.
        // The robust objective never increases.
        EXPECT_LE(CauchyCost(scene, report.inlier_mask, refined, refinement_options.loss_scale_px),
                  CauchyCost(scene, report.inlier_mask, report.cam_from_world,
                             refinement_options.loss_scale_px) *
                      (1 + 1e-9));
        EXPECT_LT(RotationErrorDegrees(refined, scene.cam_from_world), 0.1);
        const double refined_error = MeanProjectionError(scene, refined, camera);
        EXPECT_LT(refined_error, 0.25);
        sum_error += MeanProjectionError(scene, report.cam_from_world, camera);
        sum_refined_error += refined_error;
      }
    }
  }
  // The LO step already ends in least squares on the inliers, so both are near the maximum
  // likelihood pose; on average the robust refinement keeps the accuracy.
  EXPECT_LE(sum_refined_error, 1.25 * sum_error);
}

TEST(RefineAbsolutePose, ImprovesPerturbedPose) {
  const Scene scene = RandomScene(MakeCamera(CameraModelId::kSimpleRadial), 300, 0.5, 0);
  Rigid3d pose = scene.cam_from_world;
  pose.rotation = pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(
                                      0.02, Eigen::Vector3d(1, 2, 3).normalized()));
  pose.translation += Eigen::Vector3d(0.05, -0.05, 0.1);
  Camera camera = scene.camera;
  const double initial_error = MeanProjectionError(scene, pose, camera);
  const std::vector<char> all(scene.points2D.size(), 1);
  ASSERT_TRUE(RefineAbsolutePose({}, all, scene.points2D, scene.points3D, &pose, &camera));
  const double refined_error = MeanProjectionError(scene, pose, camera);
  EXPECT_LT(refined_error, 0.1);
  EXPECT_LT(refined_error, 0.01 * initial_error);
  EXPECT_NEAR(pose.rotation.norm(), 1, 1e-12);
}

// With the intrinsics constant the refinement is its own Levenberg-Marquardt: it must end at
// a minimum of the robust cost, also with outliers kept among the inliers it is given.
TEST(RefineAbsolutePose, EndsAtAMinimumOfTheRobustCost) {
  const AbsolutePoseRefinementOptions options;
  for (CameraModelId model_id : {CameraModelId::kSimpleRadial, CameraModelId::kOpenCV}) {
    const Scene scene = RandomScene(MakeCamera(model_id), 400, 1.0, 0.1);
    const std::vector<char> all(scene.points2D.size(), 1);
    Rigid3d pose = scene.cam_from_world;
    pose.rotation = pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(
                                        0.01, Eigen::Vector3d(-1, 2, 1).normalized()));
    pose.translation += Eigen::Vector3d(-0.03, 0.02, 0.05);
    Camera camera = scene.camera;
    ASSERT_TRUE(RefineAbsolutePose(options, all, scene.points2D, scene.points3D, &pose, &camera));
    const double cost = CauchyCost(scene, all, pose, options.loss_scale_px);
    // No small move along any of the six degrees of freedom lowers the cost.
    for (int axis = 0; axis < 6; ++axis) {
      for (double sign : {-1.0, 1.0}) {
        Rigid3d moved = pose;
        if (axis < 3) {
          moved.rotation =
              Eigen::Quaterniond(Eigen::AngleAxisd(sign * 1e-5, Eigen::Vector3d::Unit(axis))) *
              pose.rotation;
        } else {
          moved.translation(axis - 3) += sign * 1e-5 * pose.translation.norm();
        }
        EXPECT_GE(CauchyCost(scene, all, moved, options.loss_scale_px), cost * (1 - 1e-12))
            << "axis " << axis << " sign " << sign;
      }
    }
    EXPECT_LT(RotationErrorDegrees(pose, scene.cam_from_world), 0.05);
  }
}

TEST(RefineAbsolutePose, RefinesFocalLengthWithPrincipalPointFixed) {
  const Scene scene = RandomScene(MakeCamera(CameraModelId::kSimpleRadial), 400, 0.5, 0.3);
  Camera camera = scene.camera;
  camera.SetFocalLength(1.04 * scene.camera.MeanFocalLength());
  camera.params[3] = 0;
  const AbsolutePoseReport report =
      EstimateAbsolutePose(camera, scene.points2D, scene.points3D, {});
  ASSERT_TRUE(report.success);
  Rigid3d pose = report.cam_from_world;
  AbsolutePoseRefinementOptions options;
  options.refine_focal_length = true;
  options.refine_extra_params = true;
  ASSERT_TRUE(RefineAbsolutePose(options, report.inlier_mask, scene.points2D, scene.points3D, &pose,
                                 &camera));
  EXPECT_NEAR(camera.MeanFocalLength(), 1000, 5);
  EXPECT_NEAR(camera.params[3], -0.08, 0.01);
  EXPECT_EQ(camera.PrincipalPointX(), scene.camera.PrincipalPointX());
  EXPECT_EQ(camera.PrincipalPointY(), scene.camera.PrincipalPointY());
  EXPECT_LT(RotationErrorDegrees(pose, scene.cam_from_world), 0.1);
  EXPECT_LT(MeanProjectionError(scene, pose, camera), 0.2);

  // Only the focal length: the distortion parameter stays put.
  Camera focal_only = scene.camera;
  focal_only.SetFocalLength(980);
  options.refine_extra_params = false;
  Rigid3d pose2 = report.cam_from_world;
  ASSERT_TRUE(RefineAbsolutePose(options, report.inlier_mask, scene.points2D, scene.points3D,
                                 &pose2, &focal_only));
  EXPECT_EQ(focal_only.params[3], scene.camera.params[3]);
  EXPECT_NEAR(focal_only.MeanFocalLength(), 1000, 5);
}

TEST(EstimateAbsolutePose, DegenerateInputFailsWithoutCrash) {
  const Camera camera = MakeCamera(CameraModelId::kSimpleRadial);
  const AbsolutePoseEstimationOptions options;
  // Empty and too few.
  EXPECT_FALSE(EstimateAbsolutePose(camera, {}, {}, options).success);
  Scene scene = RandomScene(camera, 3, 0, 0);
  AbsolutePoseReport report = EstimateAbsolutePose(camera, scene.points2D, scene.points3D, options);
  EXPECT_FALSE(report.success);
  EXPECT_EQ(report.inlier_mask.size(), 3u);

  // Collinear world points.
  scene = RandomScene(camera, 50, 0, 0);
  for (size_t i = 0; i < scene.points3D.size(); ++i) {
    scene.points3D[i] = Eigen::Vector3d(1, 2, 3) + 0.1 * i * Eigen::Vector3d(1, -1, 0.5);
  }
  EXPECT_FALSE(EstimateAbsolutePose(camera, scene.points2D, scene.points3D, options).success);

  // Non-finite entries are ignored; all non-finite fails.
  scene = RandomScene(camera, 100, 0.5, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  scene.points2D[5].x() = nan;
  scene.points3D[17].z() = inf;
  report = EstimateAbsolutePose(camera, scene.points2D, scene.points3D, options);
  ASSERT_TRUE(report.success);
  EXPECT_FALSE(report.inlier_mask[5]);
  EXPECT_FALSE(report.inlier_mask[17]);
  EXPECT_GE(report.num_inliers, 95u);
  std::vector<Eigen::Vector2d> nan2D(20, Eigen::Vector2d(nan, nan));
  std::vector<Eigen::Vector3d> nan3D(20, Eigen::Vector3d(nan, 0, inf));
  EXPECT_FALSE(EstimateAbsolutePose(camera, nan2D, nan3D, options).success);

  // A camera with unusable intrinsics.
  Camera bad_camera = camera;
  bad_camera.SetFocalLength(0);
  EXPECT_FALSE(EstimateAbsolutePose(bad_camera, scene.points2D, scene.points3D, options).success);
  bad_camera.SetFocalLength(nan);
  EXPECT_FALSE(EstimateAbsolutePose(bad_camera, scene.points2D, scene.points3D, options).success);

  // Programming errors throw.
  scene.points3D.pop_back();
  EXPECT_THROW(EstimateAbsolutePose(camera, scene.points2D, scene.points3D, options), CheckError);
  AbsolutePoseEstimationOptions bad_options;
  bad_options.ransac.max_error = -1;
  EXPECT_THROW(EstimateAbsolutePose(camera, {}, {}, bad_options), CheckError);
}

TEST(RefineAbsolutePose, DegenerateInputFailsWithoutCrash) {
  Scene scene = RandomScene(MakeCamera(CameraModelId::kPinhole), 50, 0.5, 0);
  const AbsolutePoseRefinementOptions options;
  Camera camera = scene.camera;
  Rigid3d pose = scene.cam_from_world;
  // No inliers.
  EXPECT_FALSE(RefineAbsolutePose(options, std::vector<char>(50, 0), scene.points2D, scene.points3D,
                                  &pose, &camera));
  // Non-finite pose.
  std::vector<char> all(50, 1);
  pose.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(RefineAbsolutePose(options, all, scene.points2D, scene.points3D, &pose, &camera));
  // Non-finite points are skipped.
  pose = scene.cam_from_world;
  scene.points3D[3].x() = std::numeric_limits<double>::infinity();
  scene.points2D[8].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(RefineAbsolutePose(options, all, scene.points2D, scene.points3D, &pose, &camera));
  EXPECT_TRUE(pose.translation.allFinite());
  EXPECT_LT(RotationErrorDegrees(pose, scene.cam_from_world), 0.1);
  // Mask of the wrong size.
  EXPECT_THROW(RefineAbsolutePose(options, std::vector<char>(3, 1), scene.points2D, scene.points3D,
                                  &pose, &camera),
               CheckError);
}

}  // namespace
}  // namespace parallax
