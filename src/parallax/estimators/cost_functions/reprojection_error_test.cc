#include "parallax/estimators/cost_functions/reprojection_error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "parallax/geometry/testing/camera_model_params.h"
#include "parallax/math/random.h"

namespace parallax {
namespace {

// Parameters of one observation: a random pose looking at a point in front of the camera and
// plausible intrinsics with some distortion.
struct Observation {
  Eigen::Quaterniond rotation;
  Eigen::Vector3d translation;
  Eigen::Vector3d point;
  std::vector<double> params;
  Eigen::Vector2d observed;
};

template <typename Model>
Observation RandomObservation() {
  Observation obs;
  obs.rotation = Eigen::Quaterniond(RandomGaussian(0.0, 1.0), RandomGaussian(0.0, 1.0),
                                    RandomGaussian(0.0, 1.0), RandomGaussian(0.0, 1.0))
                     .normalized();
  obs.translation =
      Eigen::Vector3d(RandomGaussian(0.0, 1.0), RandomGaussian(0.0, 1.0), RandomGaussian(0.0, 1.0));
  // A point along one of the model's test rays (up to 95 degrees off the axis for fisheyes,
  // the whole sphere for EQUIRECTANGULAR), with test intrinsics perturbed by up to 2 %.
  const std::vector<Eigen::Vector3d> rays = TestRays(Model::kId);
  const Eigen::Vector3d ray =
      rays[static_cast<size_t>(RandomUniformInteger(0, static_cast<int64_t>(rays.size()) - 1))];
  const Eigen::Vector3d in_cam = RandomUniformReal(2.0, 6.0) * ray;
  obs.point = obs.rotation.inverse() * (in_cam - obs.translation);
  obs.params = TestCameraParams(Model::kId);
  for (double& param : obs.params) param *= RandomUniformReal(0.98, 1.02);
  obs.observed = Eigen::Vector2d(RandomUniformReal(0.0, 640.0), RandomUniformReal(0.0, 480.0));
  return obs;
}

// Evaluates a cost function; `wanted[i]` says whether block i's Jacobian is requested.
struct Evaluation {
  Eigen::Vector2d residual;
  std::vector<std::vector<double>> jacobians;
};

Evaluation Evaluate(const ceres::CostFunction& cost, Observation& obs,
                    const std::vector<bool>& wanted) {
  const std::vector<int> sizes = {4, 3, 3, static_cast<int>(obs.params.size())};
  const double* parameters[] = {obs.rotation.coeffs().data(), obs.translation.data(),
                                obs.point.data(), obs.params.data()};
  Evaluation evaluation;
  evaluation.jacobians.resize(4);
  double* jacobian_ptrs[4] = {nullptr, nullptr, nullptr, nullptr};
  for (int i = 0; i < 4; ++i) {
    if (!wanted[i]) continue;
    evaluation.jacobians[i].assign(2 * sizes[i], std::numeric_limits<double>::quiet_NaN());
    jacobian_ptrs[i] = evaluation.jacobians[i].data();
  }
  const bool any = wanted[0] || wanted[1] || wanted[2] || wanted[3];
  EXPECT_TRUE(cost.Evaluate(parameters, evaluation.residual.data(), any ? jacobian_ptrs : nullptr));
  return evaluation;
}

template <typename Model>
void ExpectAnalyticMatchesAutoDiff() {
  SCOPED_TRACE(Model::kName);
  for (int trial = 0; trial < 50; ++trial) {
    Observation obs = RandomObservation<Model>();
    const std::unique_ptr<ceres::CostFunction> analytic_obs(
        ReprojectionErrorCostFunction<Model>::Create(obs.observed));
    const std::unique_ptr<ceres::CostFunction> autodiff(
        ReprojectionErrorFunctor<Model>::CreateAutoDiff(obs.observed));
    // Every combination of requested blocks, as Ceres asks for constant blocks' Jacobians
    // only when they vary.
    for (int mask = 0; mask < 16; ++mask) {
      const std::vector<bool> wanted = {(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0,
                                        (mask & 8) != 0};
      const Evaluation expected = Evaluate(*autodiff, obs, {true, true, true, true});
      const Evaluation actual = Evaluate(*analytic_obs, obs, wanted);
      EXPECT_NEAR((actual.residual - expected.residual).norm(), 0.0,
                  1e-9 * (1.0 + expected.residual.norm()));
      for (int i = 0; i < 4; ++i) {
        if (!wanted[i]) continue;
        ASSERT_EQ(actual.jacobians[i].size(), expected.jacobians[i].size());
        for (size_t k = 0; k < actual.jacobians[i].size(); ++k) {
          const double scale = 1.0 + std::abs(expected.jacobians[i][k]);
          EXPECT_NEAR(actual.jacobians[i][k], expected.jacobians[i][k], 1e-9 * scale)
              << "block " << i << " entry " << k;
        }
      }
    }
  }
}

TEST(ReprojectionErrorCostFunction, AnalyticJacobiansMatchAutomaticForEveryModel) {
  SetPRNGSeed(11);
  // The chain rule through the pose is the same for every model; these cover each way a
  // projection is written (pinhole by hand, distortion, fisheye, closed forms, the sphere)
  // and the largest parameter block. ProjectionJacobiansMatchFiniteDifferencesForEveryModel
  // checks every model's projection.
  ExpectAnalyticMatchesAutoDiff<SimplePinholeModel>();
  ExpectAnalyticMatchesAutoDiff<PinholeModel>();
  ExpectAnalyticMatchesAutoDiff<SimpleRadialModel>();
  ExpectAnalyticMatchesAutoDiff<RadialModel>();
  ExpectAnalyticMatchesAutoDiff<OpenCVModel>();
  ExpectAnalyticMatchesAutoDiff<OpenCVFisheyeModel>();
  ExpectAnalyticMatchesAutoDiff<RadTanThinPrismFisheyeModel>();
  ExpectAnalyticMatchesAutoDiff<EUCMModel>();
  ExpectAnalyticMatchesAutoDiff<EquirectangularModel>();
}

// The dual numbers' Jacobians of every model's projection, with respect to the point in
// camera coordinates and to the intrinsics, against central differences of the projection.
template <typename Model>
void ExpectProjectionJacobiansMatchFiniteDifferences() {
  SCOPED_TRACE(Model::kName);
  constexpr int kNumParams = Model::kNumParams;
  for (int trial = 0; trial < 30; ++trial) {
    const Observation obs = RandomObservation<Model>();
    const Eigen::Vector3d in_cam = obs.rotation * obs.point + obs.translation;
    Eigen::Vector2d img;
    Eigen::Matrix<double, 2, 3> d_img_d_cam;
    Eigen::Matrix<double, 2, kNumParams, Eigen::RowMajor> d_img_d_params;
    ProjectWithJacobians<Model>(obs.params.data(), in_cam, &img, &d_img_d_cam,
                                d_img_d_params.data());
    const auto project = [&](const std::vector<double>& params, const Eigen::Vector3d& point) {
      Eigen::Vector2d xy;
      Model::ImgFromCam(params.data(), point.x(), point.y(), point.z(), &xy.x(), &xy.y());
      return xy;
    };
    EXPECT_LT((project(obs.params, in_cam) - img).norm(), 1e-9);
    for (int axis = 0; axis < 3; ++axis) {
      const double h = 1e-6 * in_cam.norm();
      Eigen::Vector3d plus = in_cam, minus = in_cam;
      plus[axis] += h;
      minus[axis] -= h;
      const Eigen::Vector2d numeric =
          (project(obs.params, plus) - project(obs.params, minus)) / (2 * h);
      EXPECT_LT((numeric - d_img_d_cam.col(axis)).norm(), 1e-5 * (1.0 + numeric.norm()))
          << "point axis " << axis;
    }
    for (int k = 0; k < kNumParams; ++k) {
      const double h = 1e-6 * std::max(1.0, std::abs(obs.params[k]));
      std::vector<double> plus = obs.params, minus = obs.params;
      plus[k] += h;
      minus[k] -= h;
      const Eigen::Vector2d numeric = (project(plus, in_cam) - project(minus, in_cam)) / (2 * h);
      EXPECT_LT((numeric - d_img_d_params.col(k)).norm(), 1e-5 * (1.0 + numeric.norm()))
          << "parameter " << k;
    }
  }
}

TEST(ReprojectionErrorCostFunction, ProjectionJacobiansMatchFiniteDifferencesForEveryModel) {
  SetPRNGSeed(15);
#define PARALLAX_EXPECT_FINITE_DIFFERENCES(Name) \
  ExpectProjectionJacobiansMatchFiniteDifferences<Name##Model>();
  PARALLAX_CAMERA_MODELS(PARALLAX_EXPECT_FINITE_DIFFERENCES)
#undef PARALLAX_EXPECT_FINITE_DIFFERENCES
}

// Without the intrinsics' Jacobian, the pinholes' projection is written by hand; it repeats
// the dual numbers' arithmetic, so the two give the same bits (bundle adjustment's models do
// not depend on which one ran).
template <typename Model>
void ExpectHandWrittenProjectionIsTheDualNumbers() {
  SCOPED_TRACE(Model::kName);
  for (int trial = 0; trial < 100; ++trial) {
    const Observation obs = RandomObservation<Model>();
    const Eigen::Vector3d in_cam = obs.rotation * obs.point + obs.translation;
    Eigen::Vector2d by_hand, by_jets;
    Eigen::Matrix<double, 2, 3> by_hand_jacobian, by_jets_jacobian;
    double d_params[2 * Model::kNumParams];
    ProjectWithJacobians<Model>(obs.params.data(), in_cam, &by_hand, &by_hand_jacobian, nullptr);
    ProjectWithJacobians<Model>(obs.params.data(), in_cam, &by_jets, &by_jets_jacobian, d_params);
    EXPECT_EQ(by_hand, by_jets);
    EXPECT_EQ(by_hand_jacobian, by_jets_jacobian);
  }
}

TEST(ReprojectionErrorCostFunction, PinholeProjectionByHandIsBitForBitTheDualNumbers) {
  SetPRNGSeed(14);
  ExpectHandWrittenProjectionIsTheDualNumbers<SimplePinholeModel>();
  ExpectHandWrittenProjectionIsTheDualNumbers<PinholeModel>();
}

TEST(ReprojectionErrorCostFunction, ZeroAtTheTrueProjectionAndPixelsOtherwise) {
  SetPRNGSeed(12);
  Observation obs = RandomObservation<PinholeModel>();
  const Eigen::Vector3d in_cam = obs.rotation * obs.point + obs.translation;
  double x, y;
  PinholeModel::ImgFromCam(obs.params.data(), in_cam.x(), in_cam.y(), in_cam.z(), &x, &y);
  const std::unique_ptr<ceres::CostFunction> exact(
      CreateReprojectionErrorCostFunction(CameraModelId::kPinhole, Eigen::Vector2d(x, y)));
  EXPECT_LT(Evaluate(*exact, obs, {false, false, false, false}).residual.norm(), 1e-9);
  const std::unique_ptr<ceres::CostFunction> shifted(
      CreateReprojectionErrorCostFunction(CameraModelId::kPinhole, Eigen::Vector2d(x - 3, y + 4)));
  const Eigen::Vector2d residual = Evaluate(*shifted, obs, {true, true, true, true}).residual;
  EXPECT_NEAR(residual.x(), 3.0, 1e-9);
  EXPECT_NEAR(residual.y(), -4.0, 1e-9);
}

// Along the quaternion manifold the analytic Jacobian predicts the residual's change.
TEST(ReprojectionErrorCostFunction, RotationJacobianPredictsChangeOnTheManifold) {
  SetPRNGSeed(13);
  Observation obs = RandomObservation<SimpleRadialModel>();
  const std::unique_ptr<ceres::CostFunction> cost(
      CreateReprojectionErrorCostFunction(CameraModelId::kSimpleRadial, obs.observed));
  const Evaluation at = Evaluate(*cost, obs, {true, false, false, false});
  const ceres::EigenQuaternionManifold manifold;
  double plus_jacobian[12];
  ASSERT_TRUE(manifold.PlusJacobian(obs.rotation.coeffs().data(), plus_jacobian));
  const Eigen::Map<const Eigen::Matrix<double, 2, 4, Eigen::RowMajor>> d_q(at.jacobians[0].data());
  const Eigen::Map<const Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> d_plus(plus_jacobian);
  const Eigen::Matrix<double, 2, 3> d_tangent = d_q * d_plus;
  for (int axis = 0; axis < 3; ++axis) {
    const double step = 1e-6;
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    delta[axis] = step;
    Observation moved = obs;
    ASSERT_TRUE(
        manifold.Plus(obs.rotation.coeffs().data(), delta.data(), moved.rotation.coeffs().data()));
    const Eigen::Vector2d change =
        Evaluate(*cost, moved, {false, false, false, false}).residual - at.residual;
    EXPECT_NEAR((change / step - d_tangent.col(axis)).norm(), 0.0,
                1e-4 * (1.0 + d_tangent.col(axis).norm()));
  }
}

}  // namespace
}  // namespace parallax
