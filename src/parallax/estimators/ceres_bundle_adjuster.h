#pragma once

#include <ceres/loss_function.h>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/estimators/bundle_adjustment_problem.h"

namespace parallax {

// Solves `problem` with Ceres: Levenberg-Marquardt trust region, Schur-complement linear
// solver (dense for few images, sparse otherwise), multi-threaded. `loss` may be nullptr
// (squared loss). Writes the solution into the reconstruction the problem points into.
BundleAdjustmentSummary SolveWithCeres(const BundleAdjustmentOptions& options,
                                       ceres::LossFunction* loss, BundleAdjustmentProblem* problem);

}  // namespace parallax
