#pragma once

// The Schur-complement Levenberg-Marquardt solver behind SolveWithDenseSchur and
// SolveWithSparseSchur (schur_bundle_adjuster.h), one file per part:
//   schur_linearization.cc     the layout, the cost, the Jacobians and the reduced system
//   schur_step.cc              the damped step, its model cost change, applying it
//   schur_bundle_adjuster.cc   the trust-region loop (Solve)
// Not an interface: only those files include it.

#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <type_traits>
#include <vector>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/estimators/bundle_adjustment_problem.h"
#include "parallax/estimators/reduced_camera_matrix.h"

namespace parallax {
namespace schur_detail {

// Ceres' trust-region constants, so that both solvers take the same steps.
constexpr double kInitialRadius = 1e4;
constexpr double kMaxRadius = 1e16;
constexpr double kMinRadius = 1e-32;
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr int kMaxCameraParams = kMaxCameraModelNumParams;

using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using Matrix2X = Eigen::Matrix<double, 2, Eigen::Dynamic>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;
using MatrixC3 = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxCameraParams, 3>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

using ProjectFn = void (*)(const double*, const Eigen::Vector3d&, Eigen::Vector2d*, Matrix23*,
                           double*);
using ImgFromCamFn = bool (*)(const double*, double, double, double, double*, double*);

// 0.5 rho(s) of one observation's squared residual s, and in *scale (when non-null) the
// factor sqrt(rho'(s)) that Ceres' corrector applies to residual and Jacobian for losses with

struct Parameters {
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<double>> camera_params;
};

// One observation's (loss-corrected) residual and Jacobians at the current parameters:
// pose columns are the rotation increment (left-multiplied rotation vector), then the
// translation. The intrinsics' Jacobian (free parameters in order) is kept apart, in
// camera_jacobian_values_, since most adjustments hold the cameras fixed.
struct ObservationJacobian {
  Eigen::Vector2d residual;
  Matrix26 pose;
  Matrix23 point;
};

template <typename ReducedMatrix>
class SchurSolver {
 public:
  static constexpr bool kSparse = std::is_same_v<ReducedMatrix, BlockSparseReducedMatrix>;

  SchurSolver(const BundleAdjustmentOptions& options, const ceres::LossFunction* loss,
              BundleAdjustmentProblem* problem)
      : options_(options), loss_(loss), problem_(*problem) {
    Layout();
    CopyIn();
  }

  BundleAdjustmentSummary Solve();

 private:
  void Layout();
  void CopyIn();
  void CopyOut() const;
  // Cost 0.5 sum rho(|r|^2) at `parameters`; with `linearize`, also the Jacobians, the
  // undamped reduced-system blocks U and g_c and the per-point V and g_p at them.
  double Evaluate(const Parameters& parameters, bool linearize);
  // Solves the damped system for `radius`; false when it is not positive definite.
  bool ComputeStep(double radius, Eigen::VectorXd* camera_step,
                   std::vector<Eigen::Vector3d>* point_step);
  double ModelCostChange(const Eigen::VectorXd& camera_step,
                         const std::vector<Eigen::Vector3d>& point_step) const;
  // J_c dc of the k-th observation (in observations_): its pose and intrinsics part of
  // the linearised residual change for the reduced-system step `camera_step`.
  Eigen::Vector2d CameraStepImage(size_t k, const Eigen::VectorXd& camera_step) const;
  void ApplyStep(const Eigen::VectorXd& camera_step, const std::vector<Eigen::Vector3d>& point_step,
                 Parameters* candidate) const;
  double ParameterNorm(const Parameters& parameters) const;
  // The largest move of a camera parameter in `camera_step`, in the units of
  // BundleAdjustmentOptions::camera_step_tolerance.
  double LargestCameraMove(const Eigen::VectorXd& camera_step) const;
  int NumChunks() const { return static_cast<int>(chunk_begin_.size()) - 1; }

  const BundleAdjustmentOptions& options_;
  const ceres::LossFunction* loss_;
  BundleAdjustmentProblem& problem_;
  int num_threads_ = 1;

  // Reduced system layout: offsets of variable poses and cameras (-1: constant).
  std::vector<int> pose_offset_;
  std::vector<int> camera_offset_;
  std::vector<int> camera_dim_;
  int num_camera_variables_ = 0;
  std::vector<ProjectFn> project_;
  std::vector<ImgFromCamFn> img_from_cam_;

  // The observations grouped by point (a copy: every pass walks them in this order, and
  // reaching them through an index into the problem's order missed the cache on most), and
  // the points split into chunks of about equal work (one partial reduced system each,
  // summed in chunk order: deterministic per thread count).
  std::vector<BundleAdjustmentProblem::Observation> observations_;
  std::vector<size_t> point_begin_;
  std::vector<int> chunk_begin_;

  Parameters parameters_;
  std::vector<ObservationJacobian> jacobians_;  // In observations_'s order.
  // The k-th observation's intrinsics Jacobian, 2 x its camera's free parameters.
  Eigen::Map<Matrix2X> CameraJacobian(size_t k, int dim) {
    return Eigen::Map<Matrix2X>(camera_jacobian_values_.data() + k * camera_jacobian_stride_, 2,
                                dim);
  }
  Eigen::Map<const Matrix2X> CameraJacobian(size_t k, int dim) const {
    return Eigen::Map<const Matrix2X>(camera_jacobian_values_.data() + k * camera_jacobian_stride_,
                                      2, dim);
  }
  // Only when some camera is free: per observation, room for the widest free camera (2 x 2
  // for SIMPLE_RADIAL's focal length and k1, where a fixed 2 x 8 took four times the memory).
  std::vector<double> camera_jacobian_values_;
  size_t camera_jacobian_stride_ = 0;
  ReducedMatrixStructure structure_;
  ReducedMatrix u_;  // Lower triangle.
  Eigen::VectorXd g_camera_;
  std::vector<Eigen::Matrix3d> v_;
  std::vector<Eigen::Vector3d> g_point_;
  std::vector<Eigen::Matrix3d> v_inverse_;  // Damped, from the last ComputeStep.
  // Per-chunk accumulators: U and g_c while linearising, then S and b while solving.
  std::vector<ReducedMatrix> partial_matrix_;
  int num_linear_iterations_ = 0;  // Conjugate-gradient iterations, over all steps.
  std::vector<Eigen::VectorXd> partial_vector_;
};

}  // namespace schur_detail
}  // namespace parallax
