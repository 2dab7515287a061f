#include "parallax/estimators/bundle_adjustment.h"

#include "parallax/estimators/bundle_adjustment_problem.h"
#include "parallax/estimators/ceres_bundle_adjuster.h"
#include "parallax/estimators/dense_schur_bundle_adjuster.h"
#include "parallax/estimators/robust_loss.h"
#include "parallax/util/check.h"
#include "parallax/util/timer.h"

namespace parallax {

void BundleAdjustmentOptions::Check() const {
  PARALLAX_CHECK_GE(max_dense_schur_variables, 0);
  PARALLAX_CHECK_GT(loss_scale_px, 0.0);
  PARALLAX_CHECK_GE(max_num_iterations, 0);
  PARALLAX_CHECK_GE(function_tolerance, 0.0);
  PARALLAX_CHECK_GE(gradient_tolerance, 0.0);
  PARALLAX_CHECK_GE(parameter_tolerance, 0.0);
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
  const bool dense_schur =
      options.solver == BundleAdjustmentSolver::kDenseSchur ||
      (options.solver == BundleAdjustmentSolver::kAuto &&
       NumReducedCameraVariables(problem) <= static_cast<size_t>(options.max_dense_schur_variables));
  summary = dense_schur ? SolveWithDenseSchur(options, loss.get(), &problem)
                        : SolveWithCeres(options, loss.get(), &problem);

  // Both solvers keep quaternions on the unit sphere only up to round-off.
  for (const image_t image_id : config.images) {
    reconstruction->GetImage(image_id).cam_from_world.rotation.normalize();
  }
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

}  // namespace parallax
