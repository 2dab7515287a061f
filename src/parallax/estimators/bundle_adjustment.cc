#include "parallax/estimators/bundle_adjustment.h"

#include "parallax/estimators/bundle_adjustment_problem.h"
#include "parallax/estimators/ceres_bundle_adjuster.h"
#include "parallax/estimators/robust_loss.h"
#include "parallax/estimators/schur_bundle_adjuster.h"
#include "parallax/util/check.h"
#include "parallax/util/timer.h"

namespace parallax {

std::optional<BundleAdjustmentSolver> BundleAdjustmentSolverFromName(const std::string& name) {
  if (name == "auto") return BundleAdjustmentSolver::kAuto;
  if (name == "dense-schur") return BundleAdjustmentSolver::kDenseSchur;
  if (name == "sparse-schur") return BundleAdjustmentSolver::kSparseSchur;
  if (name == "ceres") return BundleAdjustmentSolver::kCeres;
  if (name == "ceres-iterative") return BundleAdjustmentSolver::kCeresIterative;
  return std::nullopt;
}

std::optional<LossFunctionType> LossFunctionTypeFromName(const std::string& name) {
  if (name == "squared") return LossFunctionType::kTrivial;
  if (name == "huber") return LossFunctionType::kHuber;
  if (name == "soft-l1") return LossFunctionType::kSoftLOne;
  if (name == "cauchy") return LossFunctionType::kCauchy;
  return std::nullopt;
}

const char* LossFunctionName(LossFunctionType type) {
  switch (type) {
    case LossFunctionType::kTrivial:
      return "squared";
    case LossFunctionType::kHuber:
      return "huber";
    case LossFunctionType::kSoftLOne:
      return "soft-l1";
    case LossFunctionType::kCauchy:
      return "cauchy";
  }
  return "unknown";
}

BundleAdjustmentConfig WholeModelConfig(const Reconstruction& reconstruction, bool fix_poses) {
  BundleAdjustmentConfig config;
  const std::vector<image_t> image_ids = reconstruction.RegImageIds();
  for (const image_t image_id : image_ids) {
    config.AddImage(image_id);
    if (fix_poses) config.SetConstantPose(image_id);
  }
  if (!image_ids.empty()) config.SetConstantPose(image_ids[0]);
  if (image_ids.size() > 1 && !fix_poses) {
    // The largest coordinate: one near zero would leave the scale free.
    int coordinate = 0;
    reconstruction.GetImage(image_ids[1])
        .cam_from_world.translation.cwiseAbs()
        .maxCoeff(&coordinate);
    config.constant_translation_coordinates.insert({image_ids[1], coordinate});
  }
  return config;
}

void BundleAdjustmentOptions::Check() const {
  PARALLAX_CHECK_GE(max_dense_schur_variables, 0);
  PARALLAX_CHECK_GE(conjugate_gradient.max_num_iterations, 1);
  PARALLAX_CHECK_GT(conjugate_gradient.relative_tolerance, 0.0);
  PARALLAX_CHECK_GT(loss_scale_px, 0.0);
  PARALLAX_CHECK_GE(max_num_iterations, 0);
  PARALLAX_CHECK_GE(function_tolerance, 0.0);
  PARALLAX_CHECK_GE(gradient_tolerance, 0.0);
  PARALLAX_CHECK_GE(parameter_tolerance, 0.0);
  PARALLAX_CHECK_GE(camera_step_tolerance, 0.0);
  PARALLAX_CHECK(num_threads == -1 || num_threads > 0);
}

BundleAdjustmentSummary BundleAdjust(const BundleAdjustmentOptions& options,
                                     const BundleAdjustmentConfig& config,
                                     Reconstruction* reconstruction) {
  options.Check();
  PARALLAX_CHECK(reconstruction != nullptr);
  const Timer timer;
  BundleAdjustmentSummary summary;
  if (config.images.empty()) {
    summary.termination = "empty configuration";
    return summary;
  }
  BundleAdjustmentProblem problem = GatherBundleAdjustmentProblem(options, config, reconstruction);
  if (problem.observations.empty()) {
    summary.termination = "no observations in the configured images";
    return summary;
  }

  const std::unique_ptr<ceres::LossFunction> loss =
      CreateLossFunction(options.loss_function, options.loss_scale_px);
  BundleAdjustmentSolver solver = options.solver;
  if (solver == BundleAdjustmentSolver::kAuto) {
    solver =
        NumReducedCameraVariables(problem) <= static_cast<size_t>(options.max_dense_schur_variables)
            ? BundleAdjustmentSolver::kDenseSchur
            : BundleAdjustmentSolver::kSparseSchur;
  }
  switch (solver) {
    case BundleAdjustmentSolver::kDenseSchur:
      summary = SolveWithDenseSchur(options, loss.get(), &problem);
      break;
    case BundleAdjustmentSolver::kSparseSchur:
      summary = SolveWithSparseSchur(options, loss.get(), &problem);
      break;
    default:
      summary = SolveWithCeres(options, loss.get(), &problem);
  }

  // The solvers keep quaternions on the unit sphere only up to round-off.
  // Constant poses are left to the bit: normalising one that is off the sphere by round-off
  // would move the gauge.
  for (const image_t image_id : config.images) {
    if (config.constant_poses.count(image_id) > 0) continue;
    reconstruction->GetImage(image_id).cam_from_world.rotation.normalize();
  }
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

}  // namespace parallax
