#include "parallax/estimators/bundle_adjustment.h"

#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <vector>

#include "parallax/geometry/testing/camera_model_params.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

constexpr double kFocalLength = 800;
constexpr size_t kWidth = 1000;
constexpr size_t kHeight = 800;

struct SceneOptions {
  int num_images = 8;
  int num_points = 300;
  // 0: every image sees every point; else each point is seen by this many consecutive images.
  int track_length = 0;
  double noise_px = 0;
  // The camera; SIMPLE_RADIAL with k = 0.02 when unset.
  std::optional<Camera> camera;
};

Rigid3d LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitY()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d rotation;
  rotation << x.transpose(), y.transpose(), z.transpose();
  return Rigid3d(rotation, -rotation * center);
}

// Cameras on a circle of radius 6 looking near the origin at points in a 3 m cube; exact
// projections through a SIMPLE_RADIAL camera plus optional Gaussian pixel noise.
Reconstruction SynthesizeScene(const SceneOptions& options) {
  Reconstruction reconstruction;
  Camera camera = Camera::Create(1, CameraModelId::kSimpleRadial, kFocalLength, kWidth, kHeight);
  camera.params[3] = 0.02;
  if (options.camera) camera = *options.camera;
  reconstruction.AddCamera(camera);

  std::vector<Image> images(options.num_images);
  for (int i = 0; i < options.num_images; ++i) {
    const double angle = 2 * M_PI * i / options.num_images;
    const Eigen::Vector3d center(6 * std::cos(angle), RandomUniformReal(-0.5, 0.5),
                                 6 * std::sin(angle));
    const Eigen::Vector3d target(RandomUniformReal(-0.3, 0.3), RandomUniformReal(-0.3, 0.3),
                                 RandomUniformReal(-0.3, 0.3));
    images[i].image_id = static_cast<image_t>(i + 1);
    images[i].camera_id = 1;
    images[i].name = "image" + std::to_string(i + 1) + ".jpg";
    images[i].cam_from_world = LookAt(center, target);
  }

  std::vector<Eigen::Vector3d> points(options.num_points);
  std::vector<Track> tracks(options.num_points);
  for (int j = 0; j < options.num_points; ++j) {
    points[j] = Eigen::Vector3d(RandomUniformReal(-1.5, 1.5), RandomUniformReal(-1.5, 1.5),
                                RandomUniformReal(-1.5, 1.5));
    const int first = static_cast<int>(RandomUniformInteger(0, options.num_images - 1));
    const int length = options.track_length > 0 ? options.track_length : options.num_images;
    for (int k = 0; k < length; ++k) {
      Image& image = images[(first + k) % options.num_images];
      Point2D point2D;
      point2D.xy =
          camera.ImgFromCam(image.cam_from_world * points[j]) +
          Eigen::Vector2d(RandomGaussian(0, options.noise_px), RandomGaussian(0, options.noise_px));
      tracks[j].AddElement(image.image_id, static_cast<point2D_t>(image.points2D.size()));
      image.points2D.push_back(point2D);
    }
  }
  for (Image& image : images) {
    const image_t image_id = image.image_id;
    reconstruction.AddImage(std::move(image));
    reconstruction.RegisterImage(image_id);
  }
  for (int j = 0; j < options.num_points; ++j) reconstruction.AddPoint3D(points[j], tracks[j]);
  return reconstruction;
}

// Moves every variable quantity of `config` away from the truth.
void Perturb(const BundleAdjustmentConfig& config, double rotation_deg, double translation,
             double point_offset, Reconstruction* reconstruction) {
  for (const image_t image_id : config.images) {
    if (config.constant_poses.count(image_id) > 0) continue;
    Rigid3d& pose = reconstruction->GetImage(image_id).cam_from_world;
    const Eigen::Vector3d axis =
        Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
            .normalized();
    pose.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(rotation_deg * M_PI / 180, axis)) * pose.rotation;
    for (int c = 0; c < 3; ++c) {
      if (config.constant_translation_coordinates.count({image_id, c}) > 0) continue;
      pose.translation[c] += RandomGaussian(0, translation);
    }
  }
  for (const auto& [point3D_id, point] : reconstruction->Points3D()) {
    Eigen::Vector3d& xyz = reconstruction->GetPoint3D(point3D_id).xyz;
    for (int c = 0; c < 3; ++c) xyz[c] += RandomGaussian(0, point_offset);
  }
}

struct SceneErrors {
  double max_rotation_deg = 0;
  double max_center = 0;
  double mean_center = 0;
  double max_point = 0;
};

SceneErrors CompareToTruth(const Reconstruction& truth, const Reconstruction& estimate) {
  SceneErrors errors;
  for (const auto& [image_id, image] : truth.Images()) {
    const Image& estimated = estimate.GetImage(image_id);
    errors.max_rotation_deg = std::max(
        errors.max_rotation_deg,
        RotationAngleDegrees(image.cam_from_world.rotation, estimated.cam_from_world.rotation));
    const double center = (image.ProjectionCenter() - estimated.ProjectionCenter()).norm();
    errors.max_center = std::max(errors.max_center, center);
    errors.mean_center += center / truth.NumImages();
  }
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    errors.max_point =
        std::max(errors.max_point, (point.xyz - estimate.GetPoint3D(point3D_id).xyz).norm());
  }
  return errors;
}

BundleAdjustmentOptions SolverOptions(BundleAdjustmentSolver solver) {
  BundleAdjustmentOptions options;
  options.solver = solver;
  return options;
}

BundleAdjustmentOptions TightOptions(BundleAdjustmentSolver solver) {
  BundleAdjustmentOptions options = SolverOptions(solver);
  options.loss_function = LossFunctionType::kTrivial;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-14;
  options.num_threads = 2;
  return options;
}

// Every case runs with both solvers.
class BundleAdjustmentSolvers : public ::testing::TestWithParam<BundleAdjustmentSolver> {};

TEST_P(BundleAdjustmentSolvers, RecoversNoiselessSceneExactly) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Perturb(config, 1.0, 0.05, 0.05, &estimate);
  EXPECT_GT(CompareToTruth(truth, estimate).max_point, 0.05);

  const BundleAdjustmentSummary summary = BundleAdjust(TightOptions(GetParam()), config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  EXPECT_EQ(summary.num_residuals, truth.NumObservations());
  EXPECT_GT(summary.num_iterations, 0);
  EXPECT_LT(summary.final_cost, 1e-12 * summary.initial_cost);
  const SceneErrors errors = CompareToTruth(truth, estimate);
  EXPECT_LT(errors.max_rotation_deg, 1e-6);
  EXPECT_LT(errors.max_center, 1e-6);
  EXPECT_LT(errors.max_point, 1e-6);
  for (const auto& [image_id, image] : estimate.Images()) {
    EXPECT_NEAR(image.cam_from_world.rotation.norm(), 1.0, 1e-14);
  }
  // Gauge blocks did not move at all.
  EXPECT_EQ(estimate.GetImage(1).cam_from_world.translation,
            truth.GetImage(1).cam_from_world.translation);
  EXPECT_EQ(estimate.GetImage(1).cam_from_world.rotation.coeffs(),
            truth.GetImage(1).cam_from_world.rotation.coeffs());
  EXPECT_EQ(estimate.GetCamera(1).params, truth.GetCamera(1).params);
}

// COLMAP's point_triangulator adjusts with the poses given: only the points move back.
TEST_P(BundleAdjustmentSolvers, FixedPosesMoveOnlyThePoints) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/true);
  EXPECT_EQ(config.constant_poses.size(), truth.NumRegImages());
  EXPECT_TRUE(config.constant_translation_coordinates.empty());
  Perturb(config, 1.0, 0.05, 0.05, &estimate);
  const BundleAdjustmentSummary summary = BundleAdjust(TightOptions(GetParam()), config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  EXPECT_LT(CompareToTruth(truth, estimate).max_point, 1e-6);
  for (const image_t image_id : truth.RegImageIds()) {
    EXPECT_EQ(estimate.GetImage(image_id).cam_from_world.translation,
              truth.GetImage(image_id).cam_from_world.translation);
  }
}

TEST_P(BundleAdjustmentSolvers, NoisyObservationsReachNoiseLevel) {
  SetPRNGSeed(3);  // Both solvers see the same scene, whichever tests ran before.
  SceneOptions scene;
  scene.noise_px = 0.5;
  const Reconstruction truth = SynthesizeScene(scene);
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Perturb(config, 0.5, 0.02, 0.02, &estimate);
  const double initial_error = estimate.UpdatePointErrors();

  BundleAdjustmentOptions options = TightOptions(GetParam());
  options.function_tolerance = 1e-8;
  const BundleAdjustmentSummary summary = BundleAdjust(options, config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  const double final_error = estimate.UpdatePointErrors();
  // The mean of |2D Gaussian| with sigma 0.5 is 0.63 px; fitting 941 of 4800 degrees of
  // freedom takes about 10 % off.
  EXPECT_LT(final_error, 0.6);
  EXPECT_GT(final_error, 0.45);
  EXPECT_LT(final_error, initial_error);
  EXPECT_LT(summary.final_cost, summary.initial_cost);
  const SceneErrors errors = CompareToTruth(truth, estimate);
  // The gauge is fixed through one noisy camera, so its error propagates to all of them.
  EXPECT_LT(errors.max_rotation_deg, 0.2) << final_error;
  EXPECT_LT(errors.max_center, 0.02) << errors.max_center << " " << final_error;
}

TEST_P(BundleAdjustmentSolvers, RefinesFocalLength) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Perturb(config, 0.2, 0.01, 0.01, &estimate);
  estimate.GetCamera(1).SetFocalLength(1.05 * kFocalLength);

  BundleAdjustmentOptions options = TightOptions(GetParam());
  options.refine_focal_length = true;
  const BundleAdjustmentSummary summary = BundleAdjust(options, config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  const Camera& camera = estimate.GetCamera(1);
  EXPECT_NEAR(camera.FocalLengthX(), kFocalLength, 1e-3 * kFocalLength);
  // Only the focal length was free; the subset manifold kept the rest bit for bit.
  for (size_t idx = 1; idx < camera.params.size(); ++idx) {
    EXPECT_EQ(camera.params[idx], truth.GetCamera(1).params[idx]);
  }
  EXPECT_LT(CompareToTruth(truth, estimate).max_center, 1e-5);
}

TEST_P(BundleAdjustmentSolvers, RefinesPrincipalPointAndDistortionOnly) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Camera& camera = estimate.GetCamera(1);
  camera.params[1] += 5;
  camera.params[2] -= 4;
  camera.params[3] = 0;

  BundleAdjustmentOptions options = TightOptions(GetParam());
  options.refine_principal_point = true;
  options.refine_extra_params = true;
  ASSERT_TRUE(BundleAdjust(options, config, &estimate).success);
  const std::vector<double>& expected = truth.GetCamera(1).params;
  EXPECT_EQ(camera.params[0], expected[0]);
  EXPECT_NEAR(camera.params[1], expected[1], 1e-6);
  EXPECT_NEAR(camera.params[2], expected[2], 1e-6);
  EXPECT_NEAR(camera.params[3], expected[3], 1e-9);
}

// A scene with 0.3 px of noise, about 5 % of its observations moved 10 to 50 px in a random
// direction, and its poses, points and gauge as WholeModelConfig and Perturb leave them.
struct SceneWithOutliers {
  Reconstruction truth, corrupted;
  BundleAdjustmentConfig config;
  size_t num_outliers = 0;
};

SceneWithOutliers MakeSceneWithOutliers() {
  // Seeded here so the outcome does not depend on which tests ran before in the process
  // (CTest runs every case in a process of its own).
  SetPRNGSeed(5);
  SceneOptions options;
  options.noise_px = 0.3;
  SceneWithOutliers scene;
  scene.truth = SynthesizeScene(options);
  scene.corrupted = scene.truth;
  for (const auto& [image_id, image] : scene.truth.Images()) {
    for (Point2D& point2D : scene.corrupted.GetImage(image_id).points2D) {
      if (RandomUniformReal(0, 1) >= 0.05) continue;
      const double angle = RandomUniformReal(0, 2 * M_PI);
      point2D.xy += RandomUniformReal(10, 50) * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      ++scene.num_outliers;
    }
  }
  scene.config = WholeModelConfig(scene.truth, /*fix_poses=*/false);
  Perturb(scene.config, 0.5, 0.02, 0.02, &scene.corrupted);
  return scene;
}

// Every camera model (16 parameters for RAD_TAN_THIN_PRISM_FISHEYE, none to refine for the
// sphere): poses, points and the intrinsics a model has come back to the truth.
TEST_P(BundleAdjustmentSolvers, EveryCameraModelAdjusts) {
  for (const CameraModelId model : kCameraModelIds) {
    SCOPED_TRACE(CameraModelName(model));
    SetPRNGSeed(8);
    SceneOptions scene;
    scene.camera = Camera::Create(1, model, 0, 640, 480);
    scene.camera->params = TestCameraParams(model);
    const Reconstruction truth = SynthesizeScene(scene);
    Reconstruction estimate = truth;
    const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
    Perturb(config, 0.2, 0.01, 0.01, &estimate);
    const std::vector<int> focal_idxs = CameraModelFocalIdxs(model);
    for (int idx : focal_idxs) estimate.GetCamera(1).params[idx] *= 1.02;

    BundleAdjustmentOptions options = TightOptions(GetParam());
    options.refine_focal_length = true;
    const BundleAdjustmentSummary summary = BundleAdjust(options, config, &estimate);
    ASSERT_TRUE(summary.success) << summary.termination;
    for (int idx : focal_idxs) {
      EXPECT_NEAR(estimate.GetCamera(1).params[idx], truth.GetCamera(1).params[idx],
                  1e-4 * truth.GetCamera(1).params[idx]);
    }
    EXPECT_EQ(estimate.GetCamera(1).params.size(), truth.GetCamera(1).params.size());
    EXPECT_LT(CompareToTruth(truth, estimate).max_center, 1e-4);
  }
}

TEST_P(BundleAdjustmentSolvers, RobustLossResistsOutliers) {
  const SceneWithOutliers scene = MakeSceneWithOutliers();
  const Reconstruction& truth = scene.truth;
  const Reconstruction& corrupted = scene.corrupted;
  const BundleAdjustmentConfig& config = scene.config;
  EXPECT_GT(scene.num_outliers, 60u);

  BundleAdjustmentOptions options = TightOptions(GetParam());
  options.function_tolerance = 1e-8;
  Reconstruction trivial = corrupted;
  ASSERT_TRUE(BundleAdjust(options, config, &trivial).success);
  options.loss_function = LossFunctionType::kCauchy;
  options.loss_scale_px = 1.0;
  Reconstruction robust = corrupted;
  ASSERT_TRUE(BundleAdjust(options, config, &robust).success);

  const SceneErrors trivial_errors = CompareToTruth(truth, trivial);
  const SceneErrors robust_errors = CompareToTruth(truth, robust);
  EXPECT_LT(robust_errors.mean_center, 0.5 * trivial_errors.mean_center);
  EXPECT_LT(robust_errors.max_rotation_deg, trivial_errors.max_rotation_deg);
  EXPECT_LT(robust_errors.max_center, 0.5 * trivial_errors.max_center);
  EXPECT_LT(robust_errors.max_center, 0.02);
  std::cout << "max centre error: trivial " << trivial_errors.max_center << ", Cauchy "
            << robust_errors.max_center << std::endl;
}

TEST_P(BundleAdjustmentSolvers, ImagesOutsideConfigStayConstant) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  // Images 1 and 2 are outside: their observations still constrain the points (and fix the
  // gauge) but their poses must not move.
  BundleAdjustmentConfig config;
  for (image_t image_id = 3; image_id <= 8; ++image_id) config.AddImage(image_id);
  Perturb(config, 1.0, 0.05, 0.05, &estimate);
  const BundleAdjustmentSummary summary = BundleAdjust(TightOptions(GetParam()), config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  EXPECT_EQ(summary.num_residuals, truth.NumObservations());
  for (image_t image_id = 1; image_id <= 2; ++image_id) {
    EXPECT_EQ(estimate.GetImage(image_id).cam_from_world.rotation.coeffs(),
              truth.GetImage(image_id).cam_from_world.rotation.coeffs());
    EXPECT_EQ(estimate.GetImage(image_id).cam_from_world.translation,
              truth.GetImage(image_id).cam_from_world.translation);
  }
  const SceneErrors errors = CompareToTruth(truth, estimate);
  EXPECT_LT(errors.max_center, 1e-6);
  EXPECT_LT(errors.max_point, 1e-6);
}

// The same scene with every image id multiplied by `factor` (points keep their ids).
Reconstruction WithImageIdsTimes(const Reconstruction& scene, image_t factor) {
  Reconstruction renumbered;
  for (const auto& [camera_id, camera] : scene.Cameras()) renumbered.AddCamera(camera);
  for (const auto& [image_id, image] : scene.Images()) {
    Image copy = image;
    copy.image_id = image_id * factor;
    copy.registered = false;
    copy.num_points3D = 0;
    for (Point2D& point2D : copy.points2D) point2D.point3D_id = kInvalidPoint3DId;
    renumbered.AddImage(copy);
    if (image.registered) renumbered.RegisterImage(copy.image_id);
  }
  for (const auto& [point3D_id, point] : scene.Points3D()) {
    Point3D copy = point;
    for (TrackElement& element : copy.track.elements) element.image_id *= factor;
    renumbered.AddPoint3DWithId(point3D_id, copy);
  }
  return renumbered;
}

// Ids far apart (as a COLMAP database may hold) take the problem's other image lookup; the
// adjustment must be the same: to the bit with Parallax's solvers, which see the same problem
// in the same order, and to rounding with Ceres, which orders its blocks by address.
TEST_P(BundleAdjustmentSolvers, ScatteredImageIdsGiveTheSameAdjustment) {
  SetPRNGSeed(11);
  const Reconstruction truth = SynthesizeScene({});
  constexpr image_t kFactor = 400000000;
  BundleAdjustmentConfig config, scattered_config;
  for (image_t image_id = 3; image_id <= 8; ++image_id) {
    config.AddImage(image_id);
    scattered_config.AddImage(image_id * kFactor);
  }
  Reconstruction estimate = truth;
  Perturb(config, 1.0, 0.05, 0.05, &estimate);
  Reconstruction scattered = WithImageIdsTimes(estimate, kFactor);
  const BundleAdjustmentOptions options = TightOptions(GetParam());
  ASSERT_TRUE(BundleAdjust(options, config, &estimate).success);
  ASSERT_TRUE(BundleAdjust(options, scattered_config, &scattered).success);
  const bool ceres = GetParam() == BundleAdjustmentSolver::kCeres ||
                     GetParam() == BundleAdjustmentSolver::kCeresIterative;
  const double tolerance = ceres ? 1e-9 : 0.0;
  for (const auto& [image_id, image] : estimate.Images()) {
    const Rigid3d& pose = scattered.GetImage(image_id * kFactor).cam_from_world;
    EXPECT_LE((pose.rotation.coeffs() - image.cam_from_world.rotation.coeffs()).norm(), tolerance)
        << image_id;
    EXPECT_LE((pose.translation - image.cam_from_world.translation).norm(), tolerance) << image_id;
  }
  for (const auto& [point3D_id, point] : estimate.Points3D()) {
    EXPECT_LE((scattered.GetPoint3D(point3D_id).xyz - point.xyz).norm(), tolerance) << point3D_id;
  }
  EXPECT_LT(CompareToTruth(truth, estimate).max_point, 1e-6);
}

TEST_P(BundleAdjustmentSolvers, ConstantCamerasAndPointsStayFixed) {
  const Reconstruction truth = SynthesizeScene({});
  Reconstruction estimate = truth;
  BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  config.constant_cameras.insert(1);
  for (point3D_t point3D_id = 1; point3D_id <= 10; ++point3D_id) {
    config.constant_points.insert(point3D_id);
  }
  Perturb(config, 0.5, 0.02, 0.0, &estimate);
  estimate.GetPoint3D(1).xyz.x() += 0.01;  // A wrong constant point stays wrong.
  const Eigen::Vector3d fixed_point = estimate.GetPoint3D(1).xyz;
  BundleAdjustmentOptions options = TightOptions(GetParam());
  options.refine_focal_length = true;
  options.refine_extra_params = true;
  ASSERT_TRUE(BundleAdjust(options, config, &estimate).success);
  EXPECT_EQ(estimate.GetCamera(1).params, truth.GetCamera(1).params);
  EXPECT_EQ(estimate.GetPoint3D(1).xyz, fixed_point);
  EXPECT_EQ(estimate.GetPoint3D(2).xyz, truth.GetPoint3D(2).xyz);
}

// 160 images: Ceres takes its sparse Schur path; the dense Schur LM a 960-variable Cholesky.
TEST_P(BundleAdjustmentSolvers, LargeProblem) {
  SceneOptions scene;
  scene.num_images = 160;
  scene.num_points = 800;
  scene.track_length = 6;
  const Reconstruction truth = SynthesizeScene(scene);
  Reconstruction estimate = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Perturb(config, 0.3, 0.01, 0.01, &estimate);
  const BundleAdjustmentSummary summary = BundleAdjust(TightOptions(GetParam()), config, &estimate);
  ASSERT_TRUE(summary.success) << summary.termination;
  const SceneErrors errors = CompareToTruth(truth, estimate);
  EXPECT_LT(errors.max_center, 1e-6);
  EXPECT_LT(errors.max_point, 1e-6);
}

TEST_P(BundleAdjustmentSolvers, EmptyOrUnobservedConfigFailsGracefully) {
  Reconstruction reconstruction = SynthesizeScene({});
  BundleAdjustmentConfig config;
  EXPECT_FALSE(BundleAdjust(SolverOptions(GetParam()), config, &reconstruction).success);

  Image lonely;
  lonely.image_id = 100;
  lonely.camera_id = 1;
  lonely.points2D.resize(5);
  reconstruction.AddImage(lonely);
  reconstruction.RegisterImage(100);
  config.AddImage(100);
  const BundleAdjustmentSummary summary =
      BundleAdjust(SolverOptions(GetParam()), config, &reconstruction);
  EXPECT_FALSE(summary.success);
  EXPECT_EQ(summary.num_residuals, 0u);

  // Together with observed images, the unobserved one is simply skipped.
  config = WholeModelConfig(reconstruction, /*fix_poses=*/false);
  config.images.erase(100);
  config.AddImage(100);
  EXPECT_TRUE(BundleAdjust(SolverOptions(GetParam()), config, &reconstruction).success);
}

INSTANTIATE_TEST_SUITE_P(, BundleAdjustmentSolvers,
                         ::testing::Values(BundleAdjustmentSolver::kDenseSchur,
                                           BundleAdjustmentSolver::kSparseSchur,
                                           BundleAdjustmentSolver::kCeres),
                         [](const auto& info) {
                           switch (info.param) {
                             case BundleAdjustmentSolver::kCeres:
                               return "Ceres";
                             case BundleAdjustmentSolver::kSparseSchur:
                               return "SparseSchur";
                             default:
                               return "DenseSchur";
                           }
                         });

// Same problem, robust loss, intrinsics refined: the solvers land on one minimum (the
// sparse Schur LM's conjugate gradients stop at a relative residual, hence its looser bar).
TEST(BundleAdjustment, SolversReachTheSameMinimum) {
  SetPRNGSeed(11);
  SceneOptions scene;
  scene.num_images = 10;
  scene.num_points = 400;
  scene.track_length = 5;
  scene.noise_px = 0.5;
  const Reconstruction truth = SynthesizeScene(scene);
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Reconstruction perturbed = truth;
  Perturb(config, 0.3, 0.01, 0.01, &perturbed);
  perturbed.GetCamera(1).params[0] *= 1.02;
  std::vector<Reconstruction> results;
  std::vector<BundleAdjustmentSummary> summaries;
  for (const auto solver : {BundleAdjustmentSolver::kDenseSchur, BundleAdjustmentSolver::kCeres,
                            BundleAdjustmentSolver::kSparseSchur}) {
    BundleAdjustmentOptions options = TightOptions(solver);
    options.loss_function = LossFunctionType::kCauchy;
    options.refine_focal_length = true;
    options.refine_extra_params = true;
    results.push_back(perturbed);
    summaries.push_back(BundleAdjust(options, config, &results.back()));
    ASSERT_TRUE(summaries.back().success) << summaries.back().termination;
  }
  EXPECT_EQ(summaries[0].solver, "dense Schur LM");
  EXPECT_EQ(summaries[1].solver, "Ceres DENSE_SCHUR");
  EXPECT_NEAR(summaries[0].initial_cost, summaries[1].initial_cost,
              1e-9 * summaries[1].initial_cost);
  EXPECT_NEAR(summaries[0].final_cost, summaries[1].final_cost, 1e-9 * summaries[1].final_cost);
  EXPECT_LT(summaries[0].final_cost, 0.1 * summaries[0].initial_cost);
  const SceneErrors difference = CompareToTruth(results[1], results[0]);
  EXPECT_LT(difference.max_center, 1e-6);
  EXPECT_LT(difference.max_point, 1e-6);
  EXPECT_NEAR(results[0].GetCamera(1).params[0], results[1].GetCamera(1).params[0], 1e-6);
  EXPECT_NEAR(results[0].GetCamera(1).params[3], results[1].GetCamera(1).params[3], 1e-9);

  EXPECT_EQ(summaries[2].solver, "sparse Schur LM (conjugate gradients)");
  EXPECT_GT(summaries[2].num_linear_iterations, 0);
  EXPECT_NEAR(summaries[2].initial_cost, summaries[0].initial_cost,
              1e-9 * summaries[0].initial_cost);
  EXPECT_NEAR(summaries[2].final_cost, summaries[0].final_cost, 1e-6 * summaries[0].final_cost);
  const SceneErrors sparse_difference = CompareToTruth(results[0], results[2]);
  EXPECT_LT(sparse_difference.max_center, 1e-5);
  EXPECT_LT(sparse_difference.max_point, 1e-5);
  EXPECT_NEAR(results[2].GetCamera(1).params[0], results[0].GetCamera(1).params[0], 1e-4);
}

// kAuto: the dense Schur LM while the reduced system fits, the sparse one above.
TEST(BundleAdjustment, AutoPicksSolverBySize) {
  SceneOptions scene;
  scene.num_images = 20;
  scene.num_points = 100;
  scene.track_length = 4;
  Reconstruction reconstruction = SynthesizeScene(scene);
  const BundleAdjustmentConfig config = WholeModelConfig(reconstruction, /*fix_poses=*/false);
  BundleAdjustmentOptions options;
  EXPECT_EQ(BundleAdjust(options, config, &reconstruction).solver, "dense Schur LM");
  options.max_dense_schur_variables = 6 * 18;  // 19 variable poses need 114.
  EXPECT_EQ(BundleAdjust(options, config, &reconstruction).solver,
            "sparse Schur LM (conjugate gradients)");
}

TEST(BundleAdjustment, SolverNames) {
  for (const auto solver : {BundleAdjustmentSolver::kAuto, BundleAdjustmentSolver::kDenseSchur,
                            BundleAdjustmentSolver::kSparseSchur, BundleAdjustmentSolver::kCeres,
                            BundleAdjustmentSolver::kCeresIterative}) {
    bool found = false;
    for (const char* name : {"auto", "dense-schur", "sparse-schur", "ceres", "ceres-iterative"}) {
      found |= BundleAdjustmentSolverFromName(name) == solver;
    }
    EXPECT_TRUE(found);
  }
  EXPECT_FALSE(BundleAdjustmentSolverFromName("sparse").has_value());
}

// Under the Cauchy loss LM creeps on (the points near the loss's knee keep moving) long after
// the cameras have settled: the camera step tolerance stops it there, in fewer iterations, with
// the cameras where the long solve leaves them.
TEST(BundleAdjustment, CameraStepToleranceStopsTheRobustCreepWithTheCamerasInPlace) {
  for (const BundleAdjustmentSolver solver :
       {BundleAdjustmentSolver::kDenseSchur, BundleAdjustmentSolver::kSparseSchur}) {
    const SceneWithOutliers scene = MakeSceneWithOutliers();
    const Reconstruction& truth = scene.truth;
    const Reconstruction& corrupted = scene.corrupted;
    const BundleAdjustmentConfig& config = scene.config;

    BundleAdjustmentOptions options = TightOptions(solver);
    options.loss_function = LossFunctionType::kCauchy;
    options.max_num_iterations = 200;
    Reconstruction long_solve = corrupted;
    const BundleAdjustmentSummary long_summary = BundleAdjust(options, config, &long_solve);
    ASSERT_TRUE(long_summary.success) << long_summary.termination;
    options.camera_step_tolerance = 3e-5;
    Reconstruction stopped = corrupted;
    const BundleAdjustmentSummary summary = BundleAdjust(options, config, &stopped);
    ASSERT_TRUE(summary.success) << summary.termination;

    EXPECT_NE(summary.termination.find("camera step tolerance"), std::string::npos)
        << summary.termination;
    EXPECT_LT(summary.num_iterations, long_summary.num_iterations);
    const SceneErrors long_errors = CompareToTruth(truth, long_solve);
    const SceneErrors errors = CompareToTruth(truth, stopped);
    EXPECT_LT(errors.mean_center, 1.02 * long_errors.mean_center);
    EXPECT_LT(errors.max_rotation_deg, 1.02 * long_errors.max_rotation_deg);
    // Where the long solve leaves them: within a small share of the error to the truth.
    const SceneErrors moved = CompareToTruth(long_solve, stopped);
    EXPECT_LT(moved.max_center, 0.05 * long_errors.mean_center);
    std::cout << (solver == BundleAdjustmentSolver::kDenseSchur ? "dense" : "sparse") << ": "
              << summary.num_iterations << " iterations against " << long_summary.num_iterations
              << "; mean centre error " << errors.mean_center << " against "
              << long_errors.mean_center << ", largest centre move " << moved.max_center
              << std::endl;
  }
}

TEST(BundleAdjustment, OptionsCheck) {
  BundleAdjustmentOptions options;
  EXPECT_NO_THROW(options.Check());
  options.loss_scale_px = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = BundleAdjustmentOptions();
  options.num_threads = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = BundleAdjustmentOptions();
  options.camera_step_tolerance = -1e-5;
  EXPECT_THROW(options.Check(), CheckError);
}

// Timing of one mapper-sized global BA; run with --gtest_also_run_disabled_tests.
TEST(BundleAdjustment, DISABLED_Timing47Images8000Points) {
  SceneOptions scene;
  scene.num_images = 47;
  scene.num_points = 8000;
  scene.track_length = 8;
  scene.noise_px = 0.5;
  const Reconstruction truth = SynthesizeScene(scene);
  Reconstruction perturbed = truth;
  const BundleAdjustmentConfig config = WholeModelConfig(truth, /*fix_poses=*/false);
  Perturb(config, 0.3, 0.01, 0.01, &perturbed);
  for (const auto solver : {BundleAdjustmentSolver::kDenseSchur, BundleAdjustmentSolver::kCeres}) {
    BundleAdjustmentOptions options = SolverOptions(solver);
    if (std::getenv("PARALLAX_BA_REPORT") != nullptr) {
      options.print_summary = true;  // The solver's report at debug level.
      SetLogLevel(LogLevel::kDebug);
    }
    Reconstruction estimate = perturbed;
    const Timer timer;
    const BundleAdjustmentSummary summary = BundleAdjust(options, config, &estimate);
    std::printf(
        "BA 47 images, 8000 points, %zu observations, %s: %.3f s wall (%.3f s in BundleAdjust), "
        "%d iterations, cost %.6g -> %.6g, %s\n",
        summary.num_residuals, summary.solver.c_str(), timer.ElapsedSeconds(), summary.seconds,
        summary.num_iterations, summary.initial_cost, summary.final_cost,
        summary.termination.c_str());
    EXPECT_TRUE(summary.success);
  }
}

}  // namespace
}  // namespace parallax
